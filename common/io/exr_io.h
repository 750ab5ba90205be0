// OpenEXR I/O, the only place OpenEXR is used.
//  - writeExr / readExr: a developed linear RGB image (FLOAT R, G, B; ZIP) with header metadata.
//  - writeFilmExr / readFilmExr: a *partial* film for exact offline merging. Every raw double sum is kept
//    bit-exactly as two UINT channels holding the high and low 32 bits of its IEEE-754 bit pattern:
//      pixel.{R,G,B}.{hi,lo}   weighted pixel sums        (Film::pixelSums)
//      count.{hi,lo}           pixel sample counts        (Film::pixelCounts)
//      splat.{R,G,B}.{hi,lo}   splat sums                 (Film::splatSums, layer 0)
//      splat<l>.{R,G,B}.{hi,lo} splat layer l > 0, for every allocated layer (Film::splatLayer)
//    plus FLOAT R, G, B: a developed preview supplied by the caller, so any EXR viewer shows
//    something sensible. The header carries the caller's metadata plus `mltfarm.format` ("partial-film")
//    and `mltfarm.formatVersion`, the film's non-finite sample count, and `mltfarm.sumsSha256`: a SHA-256
//    over the size, the non-finite count and every channel's words, checked on reading when present (a
//    file whose sums went through float, or were edited, is refused; FilmExr::sumsVerified tells).
// The keys mltfarm.format, mltfarm.formatVersion, mltfarm.nonFiniteSamples, mltfarm.sumsSha256 and OpenEXR's own
// attribute names (channels, compression, ...) are reserved: using them in metadata is an error.
// Metadata: strings become StringAttributes, numbers DoubleAttributes (OpenEXR has no 64-bit integer
// attribute; counts up to 2^53 are exact in a double). Reading returns every string and double attribute
// (int and float attributes are returned as numbers). Errors are std::runtime_error naming the file.
// Only regular files are read (a FIFO or device is refused, not opened), with a data window of at most
// 16384 pixels a side (the farm's film limit).
#pragma once
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "common/core/color.h"
#include "common/film/film.h"

namespace mlt {

struct ImageMetadata {
  std::map<std::string, std::string> strings;
  std::map<std::string, double> numbers;
  bool operator==(const ImageMetadata&) const = default;
};

struct ExrImage {
  int width = 0, height = 0;
  std::vector<Color> rgb;  // row-major from the top-left
  ImageMetadata metadata;
};

void writeExr(const std::string& path, int width, int height, const std::vector<Color>& rgb,
              const ImageMetadata& metadata);
ExrImage readExr(const std::string& path);

struct FilmExr {
  Film film;
  ImageMetadata metadata;  // without the bookkeeping attributes above
  bool sumsVerified = false;  // the file carried mltfarm.sumsSha256 and the sums matched it
};

// previewSplatScale: the scale passed to Film::develop for the FLOAT preview channels only; the raw
// sums are stored unscaled.
void writeFilmExr(const std::string& path, const Film& film, const ImageMetadata& metadata,
                  double previewSplatScale);
// The same with the preview image given (a film with several splat layers develops with several scales).
void writeFilmExr(const std::string& path, const Film& film, const ImageMetadata& metadata,
                  const std::vector<Color>& preview);
// What a partial film EXR's header says, before any pixel is read.
struct FilmExrHeader {
  int width = 0, height = 0;
  std::vector<uint32_t> splatLayers;  // ascending, 0 first
  ImageMetadata metadata;             // as FilmExr::metadata
};
// `check`, if given, sees the header before anything is allocated for the pixels; it throws to refuse
// the file (a reader compares the sizes with what it expects, e.g. the job's).
FilmExr readFilmExr(const std::string& path, const std::function<void(const FilmExrHeader&)>& check = {});
// True if the file is an EXR written by writeFilmExr (cheap: reads the header only).
bool isFilmExr(const std::string& path);

}  // namespace mlt
