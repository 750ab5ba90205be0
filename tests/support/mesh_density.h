// Reference densities of light sampling, computed from the mesh itself (independently of the light's
// own geometry code) for the chi-square tests of emitter_test and sphere_light_test.
#pragma once
#include "common/interfaces/light.h"
#include "common/scene/scene_desc.h"

namespace mlt::test {

// Moller-Trumbore in double: distance along unit w from o to triangle (p0, p1, p2), or -1.
double hitTriangle(const Vec3& o, const Vec3& w, const Vec3& p0, const Vec3& p1, const Vec3& p2);

// Solid-angle density of light.sampleLi at ref in direction w: the sum, over every (non-degenerate)
// triangle of m the ray from ref crosses, of the light's own pdfLi at that point. A direction that meets
// the mesh twice is sampled via either point (area sampling); a cone-sampled convex light gives the far
// point density 0.
double meshPdfW(const Light& light, const MeshDesc& m, const Vec3& ref, const Vec3& w);

}  // namespace mlt::test
