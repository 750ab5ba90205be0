// makeBsdf: validates a BsdfDesc and builds the BSDF (textures loaded here). Errors name desc.id.
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/bsdf/bsdfs.h"
#include "common/bsdf/make_bsdf.h"
#include "common/scene/scene_desc.h"

namespace mlt {

namespace {

[[noreturn]] void fail(const BsdfDesc& d, const std::string& what) {
  throw std::runtime_error("bsdf '" + d.id + "': " + what);
}

bool nonNegative(const Color& c) { return c.r >= 0 && c.g >= 0 && c.b >= 0 && c.isFinite(); }

void checkColor(const BsdfDesc& d, const Color& c, const char* field) {
  if (!nonNegative(c)) fail(d, std::string(field) + " must be finite and non-negative");
}
// A colour parameter: constants are checked here, bitmaps are loaded (their texels are non-negative).
TexturePtr colorTexture(const BsdfDesc& d, const TextureDesc& t, const char* field) {
  if (t.isConstant()) checkColor(d, t.value, field);
  if (t.type == TextureDesc::Type::Checkerboard) {
    checkColor(d, t.color0, field);
    checkColor(d, t.color1, field);
  }
  return makeTexture(t, d.id);
}
TexturePtr alphaTexture(const BsdfDesc& d) {
  if (!d.alphaTexture) return nullptr;
  return colorTexture(d, *d.alphaTexture, "alpha");
}

float relativeIor(const BsdfDesc& d) {
  if (!(d.intIOR > 0) || !std::isfinite(d.intIOR)) fail(d, "intIOR must be positive, got " + std::to_string(d.intIOR));
  if (!(d.extIOR > 0) || !std::isfinite(d.extIOR)) fail(d, "extIOR must be positive, got " + std::to_string(d.extIOR));
  return d.intIOR / d.extIOR;
}

float checkedAlpha(const BsdfDesc& d) {
  if (!(d.alpha > 0) || !std::isfinite(d.alpha)) fail(d, "alpha must be positive, got " + std::to_string(d.alpha));
  return d.alpha;
}

bool isTransmissive(BsdfDesc::Type t) {
  return t == BsdfDesc::Type::Dielectric || t == BsdfDesc::Type::ThinDielectric ||
         t == BsdfDesc::Type::RoughDielectric;
}

std::unique_ptr<Bsdf> build(const SceneDesc& scene, const BsdfDesc& d, int depth) {
  using T = BsdfDesc::Type;
  if (depth > 8) fail(d, "twosided nesting too deep (cycle?)");
  switch (d.type) {
    case T::Diffuse:
      return makeDiffuse(makeTexture(d.reflectance, d.id));
    case T::TwoSided: {
      if (d.nested < 0 || d.nested >= int(scene.bsdfs.size()))
        fail(d, "twosided refers to bsdf index " + std::to_string(d.nested) + " which does not exist");
      const BsdfDesc& inner = scene.bsdfs[d.nested];
      if (isTransmissive(inner.type))
        fail(d, "twosided cannot wrap the transmissive bsdf '" + inner.id + "' (Mitsuba forbids it too)");
      return makeTwoSided(build(scene, inner, depth + 1));
    }
    case T::Dielectric:
    case T::ThinDielectric: {
      const float eta = relativeIor(d);
      auto r = colorTexture(d, d.specularReflectance, "specularReflectance");
      auto t = colorTexture(d, d.specularTransmittance, "specularTransmittance");
      return d.type == T::Dielectric ? makeDielectric(eta, std::move(r), std::move(t))
                                     : makeThinDielectric(eta, std::move(r), std::move(t));
    }
    case T::RoughDielectric: {
      const float eta = relativeIor(d);
      if (std::fabs(eta - 1) < 1e-4f) fail(d, "roughdielectric with intIOR == extIOR is not supported (index-matched)");
      auto r = colorTexture(d, d.specularReflectance, "specularReflectance");
      auto t = colorTexture(d, d.specularTransmittance, "specularTransmittance");
      return makeRoughDielectric(d.distribution, checkedAlpha(d), alphaTexture(d), eta, std::move(r), std::move(t));
    }
    case T::Conductor:
    case T::RoughConductor: {
      checkColor(d, d.eta, "eta");
      checkColor(d, d.k, "k");
      auto r = colorTexture(d, d.specularReflectance, "specularReflectance");
      if (!(d.extIOR > 0)) fail(d, "extIOR must be positive");
      // Mitsuba: the conductor's eta and k are given relative to vacuum; divide by the exterior IOR.
      const Color eta = d.eta / d.extIOR, k = d.k / d.extIOR;
      if (!d.mirror && eta.isBlack() && k.isBlack()) fail(d, "conductor with eta = k = 0");
      if (d.type == T::Conductor) return makeConductor(eta, k, d.mirror, std::move(r));
      return makeRoughConductor(d.distribution, checkedAlpha(d), alphaTexture(d), eta, k, d.mirror, std::move(r));
    }
    case T::Plastic:
    case T::RoughPlastic: {
      const float eta = relativeIor(d);
      auto r = colorTexture(d, d.specularReflectance, "specularReflectance");
      auto tex = makeTexture(d.reflectance, d.id);
      if (d.alphaTexture) fail(d, "a textured alpha is supported on roughconductor and roughdielectric only");
      if (d.type == T::Plastic) return makePlastic(eta, tex, std::move(r), d.nonlinear);
      return makeRoughPlastic(d.distribution, checkedAlpha(d), eta, tex, std::move(r), d.nonlinear);
    }
  }
  fail(d, "unknown bsdf type");
}

}  // namespace

std::unique_ptr<Bsdf> makeBsdf(const SceneDesc& scene, const BsdfDesc& desc) { return build(scene, desc, 0); }

}  // namespace mlt
