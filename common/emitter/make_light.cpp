// makeLight: validates a LightDesc and dispatches on its type.
#include <stdexcept>
#include <string>

#include "common/emitter/light_factories.h"
#include "common/emitter/make_light.h"
#include "common/scene/scene_desc.h"

namespace mlt {

std::unique_ptr<Light> makeLight(const LightDesc& desc) {
  const Color& I = desc.intensity;
  if (!I.isFinite() || I.r < 0 || I.g < 0 || I.b < 0)
    throw std::runtime_error("light: intensity/irradiance/radiance must be finite and non-negative");
  if (!isFinite(desc.position)) throw std::runtime_error("light: position is not finite");
  if (!isFinite(desc.direction)) throw std::runtime_error("light: direction is not finite");
  switch (desc.type) {
    case LightDesc::Type::Point: return makePointLight(desc.position, I);
    case LightDesc::Type::Spot:
      return makeSpotLight(desc.position, desc.direction, I, desc.cutoffAngleDeg, desc.beamWidthDeg,
                           desc.spotFalloff == LightDesc::SpotFalloff::PbrtQuartic ? SpotFalloffCurve::PbrtQuartic
                                                                                   : SpotFalloffCurve::MitsubaLinear);
    case LightDesc::Type::Directional: return makeDirectionalLight(desc.direction, I);
    case LightDesc::Type::Constant: return makeConstantEnvironment(I);
  }
  throw std::runtime_error("light: unknown type " + std::to_string(static_cast<int>(desc.type)));
}

}  // namespace mlt
