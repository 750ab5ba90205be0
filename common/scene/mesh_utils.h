// Triangle-mesh helpers for the scene front ends: Mitsuba's analytic shapes tessellated in object space,
// to_world application, normal flipping and smooth-normal generation.
#pragma once
#include <string>

#include "common/core/transform.h"
#include "common/scene/scene_desc.h"

namespace mlt {

// Mitsuba's `rectangle`: [-1,1]^2 at z = 0, normal +z, uv (0,0) at (-1,-1), (1,1) at (1,1).
MeshDesc makeRectangle();
// Mitsuba's `cube`: [-1,1]^3 with outward-facing triangles (24 vertices, flat; no vertex normals).
MeshDesc makeCube();
// Mitsuba's `disk`: unit disk at z = 0, normal +z, as a fan of `segments` triangles. uv = (r, phi / 2pi).
MeshDesc makeDisk(int segments = 128);
// Unit sphere at the origin, outward-facing, smooth per-vertex normals, uv = (phi / 2pi, theta / pi).
// nTheta rings from pole to pole and nPhi segments around.
MeshDesc makeSphere(int nTheta = 64, int nPhi = 128);

// Applies `toWorld` to positions and vertex normals (inverse transpose, renormalized). When
// `keepOrientation` is set and the transform mirrors (det < 0), the winding is reversed so the geometric
// normal (from the winding) stays the transformed object-space normal, as for Mitsuba's analytic shapes.
// Mitsuba's triangle meshes take their geometric normal from world-space winding: pass false for those.
void transformMesh(MeshDesc& mesh, const Transform& toWorld, bool keepOrientation);

// Reverses the winding of every triangle and negates vertex normals (Mitsuba's flip_normals).
void flipMesh(MeshDesc& mesh);

// Replaces mesh.normals with angle-weighted averages of adjacent face normals (Mitsuba computes these
// for meshes without normals unless face_normals is set).
void computeSmoothNormals(MeshDesc& mesh);

// The mesh's total triangle area (world space once transformed) is positive and finite, as an area
// light needs (common/emitter/area_light.cpp).
bool hasPositiveArea(const MeshDesc& mesh);

// Throws std::runtime_error (message without location) if an index is out of range, a value is not
// finite, or the per-vertex arrays have inconsistent sizes.
void validateMesh(const MeshDesc& mesh);

}  // namespace mlt
