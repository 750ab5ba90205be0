// Constructors of the concrete BSDFs (one file each; Mitsuba semantics). makeBsdf (make_bsdf.h,
// make_bsdf.cpp) validates a BsdfDesc and calls these. All BSDFs work in the local shading frame with
// wo and wi pointing away from the surface, z > 0 being the exterior / front side.
#pragma once
#include <memory>

#include "common/bsdf/texture.h"
#include "common/interfaces/bsdf.h"
#include "common/scene/scene_desc.h"

namespace mlt {

using TexturePtr = std::shared_ptr<const Texture>;

// Lambertian, one-sided: zero unless both directions are on the front side.
std::unique_ptr<Bsdf> makeDiffuse(TexturePtr reflectance);
// Applies `nested` on both sides by mirroring back-side directions to the front.
std::unique_ptr<Bsdf> makeTwoSided(std::unique_ptr<Bsdf> nested);
// Smooth glass; eta = intIOR / extIOR.
// Colour parameters are textures evaluated at the hit's uv (BsdfQuery::uv / albedo's uv), so eval, pdf,
// sample and every caller see the same value; a constant is a ConstantTexture. `alphaTex` (may be null)
// replaces the constant alpha with textureAlpha(*alphaTex, uv).
std::unique_ptr<Bsdf> makeDielectric(float eta, TexturePtr specularReflectance, TexturePtr specularTransmittance);
// Thin slab of glass (no refraction, multiple internal reflections folded into R and T).
std::unique_ptr<Bsdf> makeThinDielectric(float eta, TexturePtr specularReflectance, TexturePtr specularTransmittance);
// Smooth metal; eta, k relative to the exterior; mirror = F is 1.
std::unique_ptr<Bsdf> makeConductor(Color eta, Color k, bool mirror, TexturePtr specularReflectance);
std::unique_ptr<Bsdf> makeRoughConductor(MicrofacetType dist, float alpha, TexturePtr alphaTex, Color eta, Color k,
                                         bool mirror, TexturePtr specularReflectance);
std::unique_ptr<Bsdf> makeRoughDielectric(MicrofacetType dist, float alpha, TexturePtr alphaTex, float eta,
                                          TexturePtr specularReflectance, TexturePtr specularTransmittance);
std::unique_ptr<Bsdf> makePlastic(float eta, TexturePtr diffuse, TexturePtr specularReflectance, bool nonlinear);
std::unique_ptr<Bsdf> makeRoughPlastic(MicrofacetType dist, float alpha, float eta, TexturePtr diffuse,
                                       TexturePtr specularReflectance, bool nonlinear);

}  // namespace mlt
