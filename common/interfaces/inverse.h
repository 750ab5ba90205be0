// Inverse sampling, for reversible-jump MLT (Bitterli et al. 2017, "Reversible Jump Metropolis Light
// Transport using Inverse Mappings"): to move a path from one sampling technique to another, the chain
// needs, for a given vertex, the primary sample numbers u with which a sampling routine would have
// produced it, and the Jacobian of that mapping.
//
// Every sampling routine of the interfaces (Bsdf::sample, Light::sampleLi / sampleLe,
// Camera::generateRay / sampleWi) has an optional inverse, `invert...`, with the same conventions:
//  - it returns the primary numbers u in [0,1)^n, such that calling the routine with u reproduces the
//    given output (up to floating-point rounding);
//  - where several u map to one output, the caller's extra uniform numbers gamma (InverseGamma below;
//    Bitterli et al. sec. 5, "probabilistic inverses") choose among them so that the inverse of a uniform
//    u is uniform again: a coordinate whose value only selects a discrete choice (a light, a BSDF
//    component, roulette) is put at a + gamma (b - a) in the choice's interval [a, b) (eq. 40); a
//    coordinate the routine does not read is gamma itself (a unit Jacobian); a mixture of techniques that
//    could all have produced the output is resolved by picking technique t with T(t) of eq. 44;
//  - `jacobian` is |det du/dx| at the output x, in the measure the routine's pdf uses (solid angle for
//    directions, area for positions; a discrete probability for delta components). For a routine that
//    is one-to-one where it is differentiable this equals the pdf it reports for x; for a mixture inverted
//    with T(t) of eq. 44 the reported value is alpha_t |J_t| / T(t) = sum_s alpha_s |J_s| (eq. 42-44, the
//    factor that enters eq. 38 once T's ratio of eq. 43 is folded in), i.e. again the routine's pdf;
//  - nullopt: the type provides no inverse (the default implementation of every invert...) or x cannot
//    be produced by the routine (its pdf is 0 there).
// Every concrete camera, light and BSDF implements them (common/camera, common/emitter, common/bsdf);
// the warps' inverses live in common/core/sampling_inverse.h.
#pragma once
#include "common/core/vec.h"

namespace mlt {

// The caller's extra uniform numbers for one inverse call: `pick` resolves discrete ambiguities (first
// which technique, by eq. 44, then - remapped inside the chosen interval - where in that interval), `fill`
// is used for coordinates the routine leaves unread (eq. 40 with [a, b) = [0, 1)).
struct InverseGamma {
  float pick = 0.5f;
  Vec2 fill{0.5f, 0.5f};
};

// Two primary numbers and the Jacobian |det du/dx| of the inverse mapping at the output x.
struct Inverse2D {
  Vec2 u;
  float jacobian = 0;
};

}  // namespace mlt
