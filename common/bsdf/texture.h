// Colour textures (Mitsuba's constant spectrum, bitmap and checkerboard), looked up by uv: reflectances,
// specular reflectance / transmittance, roughness (textureAlpha) and area-light radiance.
// The uv transform uv' = uvScale * uv + uvOffset is applied inside eval().
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "common/core/color.h"
#include "common/core/vec.h"
#include "common/scene/scene_desc.h"

namespace mlt {

class Texture {
 public:
  virtual ~Texture() = default;
  virtual Color eval(Vec2 uv) const = 0;
  // Mean over the texture's domain (Mitsuba's getAverage; used for sampling weights).
  virtual Color average() const = 0;
  // Componentwise maximum over the domain.
  virtual Color maxValue() const = 0;
};

class ConstantTexture final : public Texture {
 public:
  explicit ConstantTexture(Color c) : c_(c) {}
  Color eval(Vec2) const override { return c_; }
  Color average() const override { return c_; }
  Color maxValue() const override { return c_; }

 private:
  Color c_;
};

// Mitsuba's checkerboard: with (u', v') the transformed uv, color0 when int(2u') + int(2v') is even.
class CheckerboardTexture final : public Texture {
 public:
  CheckerboardTexture(Color c0, Color c1, Vec2 scale, Vec2 offset) : c0_(c0), c1_(c1), scale_(scale), offset_(offset) {}
  Color eval(Vec2 uv) const override;
  Color average() const override { return 0.5f * (c0_ + c1_); }
  Color maxValue() const override;

 private:
  Color c0_, c1_;
  Vec2 scale_, offset_;
};

// An 8- or 16-bit PNG/JPEG image, linear RGB after an optional sRGB decode, bilinear filtering with
// repeat wrapping. Texel (i, j) (row j from the top of the file) covers u in [i/W, (i+1)/W),
// v in [j/H, (j+1)/H): v runs down the image as in Mitsuba, whose OBJ reader flips v (flip_tex_coords)
// so that OBJ files' bottom-up v ends up top-down; the flip lives in the mesh reader, not here.
class BitmapTexture final : public Texture {
 public:
  // Throws std::runtime_error naming the file if it cannot be decoded.
  BitmapTexture(const std::string& filename, bool srgb, Vec2 scale, Vec2 offset);
  // From linear RGB texels (row-major, top row first); for tests and generated textures.
  BitmapTexture(int width, int height, std::vector<Color> texels, Vec2 scale, Vec2 offset);
  Color eval(Vec2 uv) const override;
  Color average() const override { return average_; }
  Color maxValue() const override { return max_; }
  int width() const { return w_; }
  int height() const { return h_; }
  Color texel(int x, int y) const { return texels_[size_t(y) * w_ + x]; }

 private:
  void computeStats();
  int w_ = 0, h_ = 0;
  std::vector<Color> texels_;
  Vec2 scale_, offset_;
  Color average_, max_;
};

// A roughness texture's alpha at uv: the luminance of the texture's colour (Mitsuba's eval_1 on an RGB
// texture), clamped to [1e-4, 4] so a dark texel cannot make a singular distribution.
float textureAlpha(const Texture& t, Vec2 uv);

// sRGB transfer function decode (IEC 61966-2-1).
float srgbToLinear(float v);

// Builds a texture from its description. `kind` and `owner` (e.g. "bsdf" and its id) are named in error
// messages.
std::shared_ptr<const Texture> makeTexture(const TextureDesc& desc, const std::string& owner, const char* kind = "bsdf");

}  // namespace mlt
