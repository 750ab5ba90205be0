// Inverse sampling, for reversible-jump MLT (Bitterli et al. 2017, "Reversible Jump Metropolis Light
// Transport using Inverse Mappings"): to move a path from one sampling technique to another, the chain
// needs, for a given vertex, the primary sample numbers u with which a sampling routine would have
// produced it, and the Jacobian of that mapping.
//
// Every sampling routine of the interfaces (Bsdf::sample, Light::sampleLi / sampleLe,
// Camera::generateRay / sampleWi) has an optional inverse, `invert...`, with the same conventions:
//  - it returns the primary numbers u in [0,1)^n, such that calling the routine with u reproduces the
//    given output (up to floating-point rounding);
//  - where several u map to one output (a discrete choice, e.g. a BSDF component or a triangle picked
//    through a CDF), the caller's uPick numbers choose uniformly among them, so that the inverse of a
//    uniform u is uniform again;
//  - `jacobian` is |det du/dx| at the output x, in the measure the routine's pdf uses (solid angle for
//    directions, area for positions; a discrete probability for delta components). For a routine that
//    is one-to-one where it is differentiable this equals the pdf it reports for x;
//  - nullopt: the type provides no inverse (the default implementation of every invert...) or x cannot
//    be produced by the routine (its pdf is 0 there).
// The interfaces only declare them; no concrete type implements an inverse yet.
#pragma once
#include "common/core/vec.h"

namespace mlt {

// Two primary numbers and the Jacobian |det du/dx| of the inverse mapping at the output x.
struct Inverse2D {
  Vec2 u;
  float jacobian = 0;
};

}  // namespace mlt
