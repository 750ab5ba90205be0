// pbrt-v3 scene front end -> SceneDesc (the same description the Mitsuba loader produces). The subset and
// what it refuses is listed in scenes/README.md; anything outside it that would change the image is a
// SceneError naming the file, the line and the directive or parameter.
//
// Conventions, converted here once:
//  - Handedness: pbrt's camera space has +x to the image's right (a left-handed system with +y up and +z
//    forward); ours (Mitsuba's) has +x to the image's left. CameraDesc::toWorld = inverse(CTM at Camera) *
//    scale(-1, 1, 1). Consequence: the same LookAt in both formats gives mirrored images, which is why
//    scenes exported from right-handed tools start with `Scale -1 1 1`; a pbrt file with `Scale -1 1 1`
//    before LookAt L equals a Mitsuba sensor with <lookat> L.
//  - Depth: pbrt's Integrator "maxdepth" counts bounces (scattering events; 1 = direct lighting), our
//    SceneDesc::maxDepth counts path segments (Mitsuba's max_depth; 2 = direct lighting):
//    maxDepth = maxdepth + 1. pbrt's default maxdepth 5 becomes 6.
//  - fov spans the shorter image axis (CameraDesc::FovAxis::Smaller).
//  - pbrt's materials reflect on both sides: every non-transmissive material is wrapped in twosided.
//  - Geometric normals: a triangle faces its shading normals when the mesh has N (pbrt's FaceForward),
//    else its object-space winding (pbrt flips n under handedness-swapping transforms, so the object-space
//    orientation survives; like our analytic shapes). ReverseOrientation flips meshes without N and
//    analytic shapes. Area lights emit on the front side only unless "twosided" is true.
//  - Roughness: with "remaproughness" true (pbrt's default) alpha = pbrt's RoughnessToAlpha(roughness),
//    else alpha = roughness; pbrt's microfacet model for glass and metal is Trowbridge-Reitz = GGX.
//  - Textures: checkerboard cells are 1 x 1 in pbrt's (s, t) and tex1 is at floor(s) + floor(t) even;
//    imagemap's t runs up the image (pbrt flips images in y); both are converted to our uv transform.
#pragma once
#include <string>

#include "common/scene/scene_desc.h"
#include "common/scene/scene_error.h"

namespace mlt {

// `root`: when non-empty, the scene may read only files inside this directory (scene_files.h).
SceneDesc loadPbrtScene(const std::string& path, const std::string& root = {});

// pbrt-v3's RoughnessToAlpha (a polynomial in log(roughness), roughness clamped to >= 1e-3).
float pbrtRoughnessToAlpha(float roughness);

}  // namespace mlt
