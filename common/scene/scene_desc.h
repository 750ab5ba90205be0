// The plain scene description: what a front end (Mitsuba XML today, pbrt-v3 later) produces and what
// RenderScene::build consumes. No file formats, no Embree, no XML here: just values in world space.
// Every field has a meaning in the units stated; a front end fills every field it knows and reports
// what it does not support, so nothing here is a silent default of the renderer's own.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/core/color.h"
#include "common/core/transform.h"
#include "common/core/vec.h"

namespace mlt {

// A colour that may vary over the surface: constant, image (PNG/JPEG), or checkerboard. Evaluated at the
// hit's uv by the BSDF or emitter that owns it. A Color converts to a constant texture.
struct TextureDesc {
  enum class Type { Constant, Bitmap, Checkerboard };
  TextureDesc() = default;
  TextureDesc(Color c) : value(c) {}  // NOLINT: implicit, a constant colour is a constant texture
  bool isConstant() const { return type == Type::Constant; }
  Type type = Type::Constant;
  Color value{0.5f};              // Constant
  std::string filename;           // Bitmap: absolute path, already checked to exist
  bool srgb = true;               // Bitmap: decode 8-bit values from sRGB to linear (Mitsuba's "raw" = false)
  Color color0{0.4f}, color1{0.2f};  // Checkerboard: (u,v) cells alternate, 2x2 cells per unit uv
  // uv' = uvScale * uv + uvOffset (Mitsuba's to_uv / uscale / vscale).
  Vec2 uvScale{1, 1}, uvOffset{0, 0};
};

enum class MicrofacetType { GGX, Beckmann };

struct BsdfDesc {
  enum class Type {
    Diffuse,          // reflectance
    TwoSided,         // nested: the same BSDF on both sides
    Dielectric,       // smooth glass: intIOR, extIOR, specularReflectance, specularTransmittance
    ThinDielectric,   // thin slab: same parameters
    Conductor,        // smooth metal: eta, k (complex IOR relative to extIOR), specularReflectance
    RoughConductor,   // + distribution, alpha
    RoughDielectric,  // + distribution, alpha
    Plastic,          // smooth dielectric coat over diffuse: intIOR, extIOR, reflectance (diffuse), specularReflectance, nonlinear
    RoughPlastic,     // + distribution, alpha
  };
  Type type = Type::Diffuse;
  std::string id;                 // for error messages: the XML id or "<anonymous bsdf at file:line>"
  TextureDesc reflectance;        // diffuse / plastic's diffuse_reflectance
  TextureDesc specularReflectance{Color(1.0f)}, specularTransmittance{Color(1.0f)};
  float intIOR = 1.5046f, extIOR = 1.000277f;
  Color eta{0.0f}, k{1.0f};       // conductor; eta == 0 and k == 1 with `mirror` = true: ideal mirror
  bool mirror = false;            // Mitsuba's material="none": reflect everything (F = 1)
  MicrofacetType distribution = MicrofacetType::Beckmann;
  float alpha = 0.1f;             // roughness (isotropic)
  std::optional<TextureDesc> alphaTexture;  // roughconductor / roughdielectric: alpha = luminance at uv
  bool nonlinear = false;         // plastic: Mitsuba's nonlinear internal scattering
  int nested = -1;                // TwoSided: index into SceneDesc::bsdfs
};

// A triangle mesh in world space. Analytic shapes are tessellated by the front end.
struct MeshDesc {
  std::string name;                // for messages: file name or "sphere at scene.xml:12"
  std::vector<Vec3> positions;     // world space
  std::vector<Vec3> normals;       // optional per-vertex shading normals (world space, unit); empty = flat
  std::vector<Vec2> uvs;           // optional per-vertex uv; empty = (0,0)
  std::vector<uint32_t> indices;   // 3 per triangle, counter-clockwise = front (geometric normal side)
  int bsdf = -1;                   // index into SceneDesc::bsdfs
  std::optional<Color> emission;   // area emitter radiance Le (W / (m^2 sr)), emitted on the front side
  // A textured radiance: Le(uv) from this texture at the point's uv (emission then only marks the mesh as
  // emitting). Light selection uses the texture's average.
  std::optional<TextureDesc> emissionTexture;
  // The front end made this mesh as a closed convex surface (a sphere, possibly under an affine transform).
  // An area light on it may then be sampled by the solid angle its bounding sphere subtends (area_light.cpp).
  bool convex = false;
};

struct LightDesc {
  enum class Type { Point, Spot, Directional, Constant };
  Type type = Type::Point;
  Color intensity{1.0f};           // Point/Spot: W/sr; Directional: irradiance W/m^2; Constant: radiance
  Vec3 position{0, 0, 0};          // Point, Spot
  Vec3 direction{0, 0, 1};         // Spot axis, Directional travel direction (unit)
  float cutoffAngleDeg = 20.0f;    // Spot: total cone half-angle
  float beamWidthDeg = 15.0f;      // Spot: full-intensity half-angle (smooth falloff in between)
  // Spot: the curve between beam and cutoff. Mitsuba's is linear in the angle; pbrt-v3's (coneangle,
  // conedelta: beam = coneangle - conedelta) is delta^4 with delta linear in the cosine.
  enum class SpotFalloff { MitsubaLinear, PbrtQuartic };
  SpotFalloff spotFalloff = SpotFalloff::MitsubaLinear;
};

struct CameraDesc {
  enum class Type { Perspective, ThinLens };
  enum class FovAxis { X, Y, Diagonal, Smaller, Larger };
  Type type = Type::Perspective;
  Transform toWorld;               // camera space: +z forward, +y up, +x left (Mitsuba)
  float fovDeg = 45.0f;
  FovAxis fovAxis = FovAxis::X;
  float nearClip = 1e-2f;
  float apertureRadius = 0.0f;     // ThinLens
  float focusDistance = 1.0f;      // ThinLens
  int width = 512, height = 512;   // film resolution (hdrfilm)
};

struct SceneDesc {
  std::string sourceFile;          // the top-level scene file
  std::vector<std::string> referencedFiles;  // every file the scene reads (includes, meshes, textures)
  CameraDesc camera;
  std::vector<BsdfDesc> bsdfs;
  std::vector<MeshDesc> meshes;
  std::vector<LightDesc> lights;   // non-area emitters
  // Integrator defaults read from the scene's <integrator> block (the type is ignored).
  std::optional<int> maxDepth;     // path segments; -1 = unlimited (Mitsuba)
  std::optional<int> rrDepth;
  std::optional<int> sampleCount;  // the sensor's <sampler> sample_count, if given (a hint; jobs choose spp)
  std::vector<std::string> warnings;  // e.g. "gaussian rfilter replaced by box"
};

}  // namespace mlt
