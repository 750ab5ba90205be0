// Mitsuba's `twosided` adapter.
#include "common/bsdf/bsdfs.h"

namespace mlt {

namespace {

// Mitsuba's twosided: directions on the back side are mirrored (z -> -z) so that the nested BSDF sees
// the front. Transmissive BSDFs are rejected by makeBsdf (as Mitsuba does).
class TwoSided final : public Bsdf {
 public:
  explicit TwoSided(std::unique_ptr<Bsdf> nested) : nested_(std::move(nested)) { reads_ = nested_->reads(); }

  Color eval(const Vec3& wo, const Vec3& wi, const BsdfQuery& q) const override {
    return wo.z < 0 ? nested_->eval(flip(wo), flip(wi), q) : nested_->eval(wo, wi, q);
  }
  float pdf(const Vec3& wo, const Vec3& wi, const BsdfQuery& q) const override {
    return wo.z < 0 ? nested_->pdf(flip(wo), flip(wi), q) : nested_->pdf(wo, wi, q);
  }
  std::optional<BsdfSample> sample(const Vec3& wo, float uc, Vec2 ud, const BsdfQuery& q) const override {
    if (wo.z >= 0) return nested_->sample(wo, uc, ud, q);
    std::optional<BsdfSample> s = nested_->sample(flip(wo), uc, ud, q);
    if (s) s->wi = flip(s->wi);
    return s;
  }
  std::optional<BsdfSampleInverse> invertSample(const Vec3& wo, const Vec3& wi, const InverseGamma& gamma,
                                                const BsdfQuery& q) const override {
    if (wo.z >= 0) return nested_->invertSample(wo, wi, gamma, q);
    return nested_->invertSample(flip(wo), flip(wi), gamma, q);
  }
  bool isDelta() const override { return nested_->isDelta(); }
  Color albedo(const Vec2& uv) const override { return nested_->albedo(uv); }

 private:
  static Vec3 flip(const Vec3& w) { return {w.x, w.y, -w.z}; }
  std::unique_ptr<Bsdf> nested_;
};

}  // namespace

std::unique_ptr<Bsdf> makeTwoSided(std::unique_ptr<Bsdf> nested) { return std::make_unique<TwoSided>(std::move(nested)); }

}  // namespace mlt
