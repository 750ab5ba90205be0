// Constructors of the individual light types (one file each); makeLight (make_light.h) dispatches on
// LightDesc::Type. Each validates its parameters and throws std::runtime_error naming the field.
#pragma once
#include <memory>

#include "common/core/color.h"
#include "common/core/vec.h"
#include "common/interfaces/light.h"

namespace mlt {

// Isotropic point light of intensity I (W/sr).
std::unique_ptr<Light> makePointLight(const Vec3& position, const Color& I);
// Spot light: intensity I (W/sr) on the axis, full inside beamWidth, falling to zero at cutoff (half-angles
// in degrees): linearly in the angle (Mitsuba's spot), or pbrt-v3's SpotLight::Falloff, delta^4 with
// delta = (cos theta - cos cutoff) / (cos beam - cos cutoff).
enum class SpotFalloffCurve { MitsubaLinear, PbrtQuartic };
std::unique_ptr<Light> makeSpotLight(const Vec3& position, const Vec3& axis, const Color& I, float cutoffDeg,
                                     float beamWidthDeg, SpotFalloffCurve curve = SpotFalloffCurve::MitsubaLinear);
// Directional light: irradiance E (W/m^2) on surfaces perpendicular to the travel direction d.
std::unique_ptr<Light> makeDirectionalLight(const Vec3& d, const Color& E);
// Constant environment: radiance L from every direction.
std::unique_ptr<Light> makeConstantEnvironment(const Color& L);

}  // namespace mlt
