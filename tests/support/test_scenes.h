// Analytic and small reference scenes built in code (no XML), shared by the integrator and MLT tests.
//
// Units: radiance Le in W/(m^2 sr); every scene's camera is a pinhole; film sizes are parameters so a
// test can trade resolution for speed.
#pragma once
#include "common/core/color.h"
#include "common/scene/scene_desc.h"

namespace mlt::test {

// A closed sphere of radius 1 around the origin, tessellated into 2 * res * res... (res rings x 2 res
// segments) flat triangles facing inward, Lambertian albedo rho, emitting Le on its inner side; the
// camera sits at the center. Because the enclosure is closed and uniform, the radiance along every ray
// is exactly furnaceRadiance(Le, rho, maxDepth) whatever the tessellation.
SceneDesc furnaceSphere(float Le, float rho, int res, int width = 8, int height = 8);
// Le * sum_{i < maxDepth} rho^i (paths of at most maxDepth segments); maxDepth < 0: Le / (1 - rho).
double furnaceRadiance(double Le, double rho, int maxDepth);

// A Cornell-like box [-1,1]^3 (open toward the camera at z = -1): white floor, ceiling and back wall,
// red left wall (x = -1), green right wall (x = +1), a white block, and a square area light of radiance
// `Le` just below the ceiling facing down. Camera at (0, 0, -3.6) looking toward +z, 45 degrees horizontal field of view.
SceneDesc smallCornellBox(int width, int height, Color Le = Color(10.0f));
// The box with a glass sphere (IOR 1.5) and a mirror sphere instead of the block: caustics and
// specular chains. smoothNormals: interpolated vertex normals on the spheres (shading normals).
SceneDesc cornellBoxSpecular(int width, int height, bool smoothNormals = true);
// The box without its area light, lit by a point light and a spot light (delta-position emitters).
SceneDesc cornellBoxPointSpot(int width, int height);
// The glass and mirror spheres of cornellBoxSpecular lit by cornellBoxPointSpot's two lights (caustics of
// delta-position lights).
SceneDesc cornellBoxSpecularPointSpot(int width, int height);
// Two area lights of very different size and power: a large dim panel under the ceiling (1.6 x 1.6,
// Le = 0.5) and a small bright one (0.08 x 0.08, Le = 400) inside a mirror reflector (an open cup of four
// mirror walls) near the ceiling's left corner, plus the block. Light selection by power picks the small
// light twice as often as the panel (power 8 vs 4) though the panel lights most of the room.
SceneDesc twoLightsReflector(int width, int height);
// The box with the block and, instead of the ceiling panel, a sphere light (radius 0.15, Le = 40, 16
// rings, marked convex: sampled by the solid angle it subtends from outside its bounding sphere).
SceneDesc cornellBoxSphereLight(int width, int height);

}  // namespace mlt::test
