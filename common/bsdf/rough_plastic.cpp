// Rough plastic (Mitsuba's `roughplastic`, approximated): a rough dielectric coat over a diffuse base.
//   f = f_spec + f_diff
//   f_spec(wo, wi) = specR F(wo.h) D(h) G(wo, wi, h) / (4 cos_o cos_i)            (Walter et al. 2007, eq. 20)
//   f_diff(wo, wi) = rho' T(cos_o) T(cos_i) / (pi Tavg)
// where T(mu) = 1 - R(mu) and R(mu) is the directional albedo of the white specular lobe (tabulated at
// construction by a stratified visible-normal quadrature: R = E[F(wo.m) G1(wi, m)]), and
// Tavg = 2 int_0^1 T(mu) mu dmu. Mitsuba instead tabulates the transmittance of a rough dielectric
// boundary and divides by eta^2 (1 - Fdr_int); both agree for a smooth coat, where
// Tavg = 1 - Fdr_ext = eta^2 (1 - Fdr_int). Our normalisation makes the model exactly energy-conserving:
// the diffuse albedo is rho' T(cos_o), so albedo(wo) = specR R(cos_o) + rho' T(cos_o) <= 1 for
// specR, rho' <= 1. rho' = rho (linear, default) or rho (1 - Fdr_int) / (1 - rho Fdr_int) (nonlinear,
// Mitsuba's internal-scattering colour shift expressed relative to the linear case).
// Sampling: specular lobe (visible normals) with P_spec = R w / (R w + T (1 - w)), else cosine.
#include <cmath>
#include <vector>

#include "common/bsdf/bsdfs.h"
#include "common/bsdf/fresnel.h"
#include "common/bsdf/microfacet.h"
#include "common/core/sampling.h"
#include "common/core/sampling_inverse.h"

namespace mlt {

namespace {

constexpr int kTableSize = 64;
constexpr int kStrata = 32;

class RoughPlastic final : public Bsdf {
 public:
  RoughPlastic(MicrofacetType type, float alpha, float eta, TexturePtr diffuse, TexturePtr specR, bool nonlinear)
      : mf_(type, alpha), eta_(eta), diffuse_(std::move(diffuse)), specR_(std::move(specR)), nonlinear_(nonlinear) {
    fdrInt_ = fresnelDiffuseReflectance(1 / eta_);
    const float d = luminance(diffuse_->average()), s = luminance(specR_->average());
    specularWeight_ = d + s > 0 ? s / (d + s) : 0.5f;
    buildTable();
  }

  Color eval(const Vec3& wo, const Vec3& wi, const BsdfQuery& q) const override {
    if (wo.z <= 0 || wi.z <= 0) return Color(0.0f);
    return specular(wo, wi, q.uv) + rhoEff(q.uv) * (T(wo.z) * T(wi.z) * kInvPi / tAvg_);
  }
  float pdf(const Vec3& wo, const Vec3& wi, const BsdfQuery&) const override {
    if (wo.z <= 0 || wi.z <= 0) return 0;
    const float pSpec = probSpecular(wo.z);
    const Vec3 h = normalize(wo + wi);
    const float woh = dot(wo, h);
    const float pdfSpec = woh > 0 ? mf_.pdfVisible(wo, h) / (4 * woh) : 0.0f;
    return pSpec * pdfSpec + (1 - pSpec) * cosineHemispherePdfW(wi.z);
  }
  std::optional<BsdfSample> sample(const Vec3& wo, float uc, Vec2 uDir, const BsdfQuery& q) const override {
    if (wo.z <= 0) return std::nullopt;
    BsdfSample s;
    if (uc < probSpecular(wo.z)) s.wi = reflectAbout(wo, mf_.sampleVisible(wo, uDir));
    else s.wi = sampleCosineHemisphere(uDir);
    if (s.wi.z <= 0) return std::nullopt;
    s.pdfW = pdf(wo, s.wi, q);
    if (!(s.pdfW > 0)) return std::nullopt;
    s.f = eval(wo, s.wi, q);
    s.pdfRevW = pdf(s.wi, wo, q);
    return s;
  }
  // Inverse: a mixture of two lobes that both reach every upper-hemisphere wi (eq. 34). Following
  // Bitterli et al. eq. 41-44, the lobe t is picked with T(t) = alpha_t p_t(wi) / sum_s alpha_s p_s(wi)
  // (alpha_spec = P_spec, p_spec = D_wo(h) / (4 wo.h); alpha_diff = 1 - P_spec, p_diff = cos / pi) using
  // gamma.pick, which is then remapped into the lobe's uComponent interval (eq. 40); uDir inverts the
  // lobe's routine. Reported Jacobian: alpha_t p_t / T(t) = the mixture pdf (eq. 42 with eq. 43 folded in).
  std::optional<BsdfSampleInverse> invertSample(const Vec3& wo, const Vec3& wi, const InverseGamma& gamma,
                                                const BsdfQuery& q) const override {
    if (wo.z <= 0 || wi.z <= 0) return std::nullopt;
    const float pSpec = probSpecular(wo.z);
    const Vec3 h = normalize(wo + wi);
    const float woh = dot(wo, h);
    const float pdfSpec = woh > 0 ? mf_.pdfVisible(wo, h) / (4 * woh) : 0.0f;
    const float weight[2] = {pSpec * pdfSpec, (1 - pSpec) * cosineHemispherePdfW(wi.z)};
    float gammaRest = 0;
    const int lobe = pickByWeight(weight, 2, gamma.pick, &gammaRest);
    if (lobe < 0) return std::nullopt;
    BsdfSampleInverse inv;
    if (lobe == 0) {
      const std::optional<Vec2> uDir = mf_.invertVisible(wo, h);
      if (!uDir) return std::nullopt;
      inv.uComponent = invertInterval(0, pSpec, gammaRest);
      inv.uDir = *uDir;
    } else {
      inv.uComponent = invertInterval(pSpec, 1, gammaRest);
      inv.uDir = invertCosineHemisphere(wi);
    }
    inv.jacobian = pdf(wo, wi, q);
    return inv;
  }
  bool isDelta() const override { return false; }
  Color albedo(const Vec2& uv) const override { return specR_->eval(uv) * (1 - T(1)) + rhoEff(uv) * T(1); }

 private:
  Color specular(const Vec3& wo, const Vec3& wi, Vec2 uv) const {
    const Vec3 h = normalize(wo + wi);
    const float D = mf_.D(h);
    if (D == 0) return Color(0.0f);
    const float F = fresnelDielectric(dot(wo, h), eta_);
    return specR_->eval(uv) * (F * D * mf_.G(wo, wi, h) / (4 * wo.z * wi.z));
  }
  Color rhoEff(Vec2 uv) const {
    const Color rho = diffuse_->eval(uv);
    if (!nonlinear_) return rho;
    return rho * (1 - fdrInt_) / (Color(1.0f) - rho * fdrInt_);
  }
  float probSpecular(float cosO) const {
    const float R = 1 - T(cosO);
    const float a = R * specularWeight_, b = (1 - R) * (1 - specularWeight_);
    return a + b > 0 ? a / (a + b) : 0;
  }
  // Table lookup, linear in mu; entries at mu_j = j / (N - 1) (entry 0 evaluated at a grazing 1e-4).
  float T(float mu) const {
    const float x = std::clamp(mu, 0.0f, 1.0f) * (kTableSize - 1);
    const int i = std::min(int(x), kTableSize - 2);
    const float t = x - i;
    return (1 - t) * table_[i] + t * table_[i + 1];
  }
  void buildTable() {
    table_.resize(kTableSize);
    for (int j = 0; j < kTableSize; ++j) {
      const float mu = std::fmax(1e-4f, float(j) / (kTableSize - 1));
      const Vec3 wo(std::sqrt(1 - mu * mu), 0, mu);
      // R(mu) = int f_spec cos_i dwi = E_{m ~ D_wo}[F(wo.m) G1(wi, m)] (white specular reflectance).
      double R = 0;
      for (int a = 0; a < kStrata; ++a)
        for (int b = 0; b < kStrata; ++b) {
          const Vec2 u((a + 0.5f) / kStrata, (b + 0.5f) / kStrata);
          const Vec3 m = mf_.sampleVisible(wo, u);
          const Vec3 wi = reflectAbout(wo, m);
          if (wi.z <= 0) continue;
          R += fresnelDielectric(dot(wo, m), eta_) * mf_.G1(wi, m);
        }
      table_[j] = float(1 - R / (kStrata * kStrata));
    }
    // Tavg = 2 int_0^1 T(mu) mu dmu by Simpson's rule on the interpolated table.
    const int n = 4096;
    double sum = 0;
    for (int i = 0; i <= n; ++i) {
      const double mu = double(i) / n;
      const double w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
      sum += w * T(float(mu)) * mu;
    }
    tAvg_ = float(2 * sum / (3.0 * n));
  }

  Microfacet mf_;
  float eta_;
  TexturePtr diffuse_;
  TexturePtr specR_;  // specular_reflectance at the hit's uv (alpha is not texturable: the table depends on it)
  bool nonlinear_;
  float fdrInt_, specularWeight_, tAvg_ = 1;
  std::vector<float> table_;
};

}  // namespace

std::unique_ptr<Bsdf> makeRoughPlastic(MicrofacetType type, float alpha, float eta, TexturePtr diffuse, TexturePtr specR,
                                       bool nonlinear) {
  return std::make_unique<RoughPlastic>(type, alpha, eta, std::move(diffuse), std::move(specR), nonlinear);
}

}  // namespace mlt
