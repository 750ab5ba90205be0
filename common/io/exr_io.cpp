// OpenEXR reading and writing (see exr_io.h for the file layouts).
#include "common/io/exr_io.h"

#include <ImfChannelList.h>
#include <ImfDoubleAttribute.h>
#include <ImfFloatAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfIntAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <ImfTestFile.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>

#include <fmt/format.h>

#include "common/core/sha256.h"
#include <stdexcept>

namespace mlt {

namespace {

constexpr const char* kFormatAttr = "mltfarm.format";
constexpr const char* kFormatVersionAttr = "mltfarm.formatVersion";
constexpr const char* kNonFiniteAttr = "mltfarm.nonFiniteSamples";
constexpr const char* kSumsChecksumAttr = "mltfarm.sumsSha256";
constexpr int kMaxSide = 16384;  // the farm's film limit (proto/convert.cpp kMaxFilmSide)
constexpr const char* kPartialFilmFormat = "partial-film";
constexpr int kPartialFilmVersion = 1;

// Attribute names OpenEXR itself gives a meaning to; metadata may not use them.
const std::set<std::string>& reservedNames() {
  static const std::set<std::string> names = {
      "channels", "compression", "dataWindow", "displayWindow", "lineOrder", "pixelAspectRatio",
      "screenWindowCenter", "screenWindowWidth", "tiles", "view", "name", "type", "version",
      "chunkCount", "maxSamplesPerPixel", "multiView"};
  return names;
}

// Header attributes writeFilmExr adds itself.
bool isInternal(const std::string& name) {
  return name == kFormatAttr || name == kFormatVersionAttr || name == kNonFiniteAttr || name == kSumsChecksumAttr;
}

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw std::runtime_error(path + ": " + what);
}

void addMetadata(const std::string& path, Imf::Header& header, const ImageMetadata& m) {
  for (const auto& [key, value] : m.strings) {
    if (key.empty() || reservedNames().count(key) || isInternal(key))
      fail(path, "metadata key '" + key + "' is reserved or empty");
    header.insert(key, Imf::StringAttribute(value));
  }
  for (const auto& [key, value] : m.numbers) {
    if (key.empty() || reservedNames().count(key) || isInternal(key))
      fail(path, "metadata key '" + key + "' is reserved or empty");
    if (m.strings.count(key)) fail(path, "metadata key '" + key + "' is both a string and a number");
    header.insert(key, Imf::DoubleAttribute(value));
  }
}

// Every string/number attribute except OpenEXR's own and (unless keepInternal) the mltfarm.* ones.
ImageMetadata readMetadata(const Imf::Header& header, bool keepInternal) {
  ImageMetadata m;
  for (auto it = header.begin(); it != header.end(); ++it) {
    const std::string name = it.name();
    if (reservedNames().count(name)) continue;
    if (!keepInternal && isInternal(name)) continue;
    const Imf::Attribute& a = it.attribute();
    if (auto* s = dynamic_cast<const Imf::StringAttribute*>(&a)) m.strings[name] = s->value();
    else if (auto* d = dynamic_cast<const Imf::DoubleAttribute*>(&a)) m.numbers[name] = d->value();
    else if (auto* f = dynamic_cast<const Imf::FloatAttribute*>(&a)) m.numbers[name] = f->value();
    else if (auto* i = dynamic_cast<const Imf::IntAttribute*>(&a)) m.numbers[name] = i->value();
  }
  return m;
}

// The value sizes of OpenEXR's fixed-size attribute types (ImfStandardAttributes and the Imf*Attribute
// readers of OpenEXR 3.1).
const std::map<std::string, uint64_t> kFixedAttributeSizes = {
    {"box2i", 16}, {"box2f", 16}, {"compression", 1}, {"double", 8}, {"envmap", 1}, {"float", 4}, {"int", 4},
    {"keycode", 28}, {"lineOrder", 1}, {"m33f", 36}, {"m33d", 72}, {"m44f", 64}, {"m44d", 128}, {"rational", 8},
    {"tiledesc", 9}, {"timecode", 8}, {"v2i", 8}, {"v2f", 8}, {"v2d", 16}, {"v3i", 12}, {"v3f", 12}, {"v3d", 24},
    {"deepImageState", 1}, {"chromaticities", 32}};

// OpenEXR allocates each header attribute's value at the size the file declares before reading it, so a
// damaged or hostile file could make it take gigabytes (seen by the fuzz test under AddressSanitizer: a
// 1 GB attribute in a 2 KB file). Walks the header (magic, version, then name\0 type\0 int32 size value,
// up to an empty name; a multi-part file has one such header per part and ends the list with an empty
// header) and refuses any attribute larger than the rest of the file or 64 MiB, before OpenEXR reads it.
// Multi-part files used to be left to OpenEXR, and names were allowed 255 bytes whatever the flags.
void checkHeaderSizes(const std::string& path) {
  constexpr uint64_t kMaxAttribute = 64ull << 20;
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot be opened");
  const uint64_t fileSize = std::filesystem::file_size(path);
  char start[8];
  if (!in.read(start, 8)) fail(path, "too short for an OpenEXR header");
  const bool multiPart = uint8_t(start[5]) & 0x10;
  // Names and type names: at most 31 bytes, 255 with the long-names flag. OpenEXR reads that many and goes
  // on with the next byte whether or not it was the terminator, so a longer one would make it read the
  // next size from other bytes than this walk does (the fuzz test: a size of 0x6f630000, "\0\0co").
  const size_t maxName = (uint8_t(start[5]) & 0x04) ? 255 : 31;
  uint64_t pos = 8;
  auto readString = [&](const char* what) {
    std::string sv;
    for (char c; in.get(c);) {
      ++pos;
      if (c == '\0') return sv;
      if (sv.size() >= maxName)
        fail(path, fmt::format("header: {} longer than {} bytes at offset {}", what, maxName, pos));
      sv += c;
    }
    fail(path, fmt::format("header: ends inside an attribute {}", what));
  };
  auto readU32 = [&](const std::string& name) {
    unsigned char b[4];
    if (!in.read(reinterpret_cast<char*>(b), 4)) fail(path, "header: ends inside attribute " + name.substr(0, 64));
    pos += 4;
    return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
  };
  for (int n = 0;; ++n) {
    if (n > 100000) fail(path, "header: more than 100000 attributes");
    const std::string name = readString("name");
    if (name.empty()) {  // the end of a header
      if (!multiPart || in.peek() == '\0') return;  // single part, or the empty header that ends the list
      if (in.peek() == std::char_traits<char>::eof()) fail(path, "header: the list of parts does not end");
      continue;  // the next part's header
    }
    const std::string type = readString("type");
    const uint32_t size = readU32(name);
    if (size > kMaxAttribute || pos + size > fileSize)
      fail(path, fmt::format("header: attribute '{}' declares {} bytes (the file has {} after it)", name.substr(0, 64),
                             size, fileSize - std::min(fileSize, pos)));
    // OpenEXR reads a value of a known type by the type, not by the declared size, and goes on from where
    // that left it: a size other than what the type reads would make it parse the rest of the header from
    // other bytes than this walk does. So the two must agree.
    const uint64_t start = pos;
    uint64_t reads = size;
    if (const auto fixed = kFixedAttributeSizes.find(type); fixed != kFixedAttributeSizes.end()) {
      reads = fixed->second;
    } else if (type == "chlist") {  // channels: name\0 and 16 bytes each, up to an empty name
      for (std::string channel = readString("channel name"); !channel.empty(); channel = readString("channel name")) {
        in.seekg(16, std::ios::cur);
        pos += 16;
        if (pos - start > size) break;
      }
      reads = pos - start;
    } else if (type == "preview") {  // width, height, then 4 bytes a pixel
      const uint64_t w = readU32(name), h = readU32(name);
      reads = w * h <= kMaxAttribute ? 8 + 4 * w * h : ~uint64_t(0);  // no wrap-around to a size that matches
    }
    if (reads != size)
      fail(path, fmt::format("header: attribute '{}' of type {} declares {} bytes but its value takes {}",
                             name.substr(0, 64), type.substr(0, 64), size, reads));
    in.seekg(std::streamoff(start + size), std::ios::beg);
    pos = start + size;
  }
}

// Checks existence and the magic number so the common mistakes get a clear message.
void checkReadable(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) fail(path, "no such file");
  if (std::filesystem::is_directory(path, ec)) fail(path, "is a directory, not an EXR file");
  if (!std::filesystem::is_regular_file(path, ec)) fail(path, "not a regular file (a FIFO, device or socket is not read)");
  static std::once_flag limitSet;  // OpenEXR refuses larger data windows before allocating for them
  std::call_once(limitSet, [] { Imf::Header::setMaxImageSize(kMaxSide, kMaxSide); });
  bool tiled = false, deep = false, multiPart = false;
  if (!Imf::isOpenExrFile(path.c_str(), tiled, deep, multiPart)) fail(path, "not an OpenEXR file");
  if (deep) fail(path, "deep EXR files are not supported");
  checkHeaderSizes(path);
}

struct Size {
  int width, height;
  Imath::Box2i dw;
};

Size imageSize(const std::string& path, const Imf::Header& header) {
  const Imath::Box2i dw = header.dataWindow();
  const long w = long(dw.max.x) - dw.min.x + 1, h = long(dw.max.y) - dw.min.y + 1;
  if (w <= 0 || h <= 0 || w * h > (1L << 31)) fail(path, "invalid data window");
  return {int(w), int(h), dw};
}

// Pointer such that base + x * xStride + y * yStride addresses element (x - dw.min.x, y - dw.min.y).
template <typename T>
char* slicesBase(T* data, const Size& s, size_t xStride) {
  return reinterpret_cast<char*>(data) - (ptrdiff_t(s.dw.min.x) + ptrdiff_t(s.dw.min.y) * s.width) * ptrdiff_t(xStride);
}

void writeFloatRgb(Imf::Header& header, Imf::FrameBuffer& fb, const std::vector<Color>& rgb, int width) {
  const char* names[3] = {"R", "G", "B"};
  for (int c = 0; c < 3; ++c) {
    header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
    char* base = const_cast<char*>(reinterpret_cast<const char*>(rgb.data())) + c * sizeof(float);
    fb.insert(names[c], Imf::Slice(Imf::FLOAT, base, sizeof(Color), sizeof(Color) * size_t(width)));
  }
}

}  // namespace

// ---- Developed images ------------------------------------------------------------------------------

namespace {
// Writes the frame buffer's slices under `header`; OpenEXR's errors name the file.
void writeFrame(const std::string& path, const Imf::Header& header, const Imf::FrameBuffer& fb, int height) {
  try {
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(height);
  } catch (const std::exception& e) {
    fail(path, std::string("cannot write EXR: ") + e.what());
  }
}
}  // namespace

void writeExr(const std::string& path, int width, int height, const std::vector<Color>& rgb,
              const ImageMetadata& metadata) {
  if (width <= 0 || height <= 0) fail(path, "cannot write an empty image");
  if (rgb.size() != size_t(width) * size_t(height))
    fail(path, "pixel count " + std::to_string(rgb.size()) + " does not match " + std::to_string(width) +
                   "x" + std::to_string(height));
  static_assert(sizeof(Color) == 3 * sizeof(float));
  Imf::Header header(width, height);
  header.compression() = Imf::ZIP_COMPRESSION;
  addMetadata(path, header, metadata);
  Imf::FrameBuffer fb;
  writeFloatRgb(header, fb, rgb, width);
  writeFrame(path, header, fb, height);
}

ExrImage readExr(const std::string& path) {
  checkReadable(path);
  try {
    Imf::InputFile file(path.c_str());
    const Imf::Header& header = file.header();
    const Size s = imageSize(path, header);
    ExrImage img;
    img.width = s.width;
    img.height = s.height;
    img.rgb.assign(size_t(s.width) * size_t(s.height), Color());
    img.metadata = readMetadata(header, false);
    Imf::FrameBuffer fb;
    const char* names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c) {
      if (!header.channels().findChannel(names[c])) fail(path, std::string("missing channel ") + names[c]);
      char* base = slicesBase(img.rgb.data(), s, sizeof(Color)) + c * sizeof(float);
      fb.insert(names[c], Imf::Slice(Imf::FLOAT, base, sizeof(Color), sizeof(Color) * size_t(s.width)));
    }
    file.setFrameBuffer(fb);
    file.readPixels(s.dw.min.y, s.dw.max.y);
    return img;
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).rfind(path + ":", 0) == 0) throw;
    fail(path, std::string("cannot read EXR: ") + e.what());
  } catch (const std::exception& e) {
    fail(path, std::string("cannot read EXR: ") + e.what());
  }
}

// ---- Partial films ---------------------------------------------------------------------------------

namespace {

// The raw doubles of a film as (channel base name, component inside the element, doubles per element,
// buffer): pixel sums, counts, then every allocated splat layer (layer 0 "splat", layer l "splat<l>").
struct DoubleField {
  std::string name;
  size_t offset;  // index of the component inside the element
  size_t stride;  // doubles per element
  int layer;      // -2: pixel sums, -1: counts, >= 0: splat layer
};

std::vector<DoubleField> filmFields(const std::vector<uint32_t>& layers) {
  std::vector<DoubleField> fields = {{"pixel.R", 0, 3, -2}, {"pixel.G", 1, 3, -2}, {"pixel.B", 2, 3, -2}, {"count", 0, 1, -1}};
  for (uint32_t l : layers) {
    const std::string base = l == 0 ? "splat" : "splat" + std::to_string(l);
    for (size_t c = 0; c < 3; ++c) fields.push_back({base + "." + "RGB"[c], c, 3, int(l)});
  }
  return fields;
}

// The splat layers a partial film EXR holds, from its channel names ("splat<l>.R.hi"; layer 0 is "splat").
std::vector<uint32_t> layersInHeader(const std::string& path, const Imf::Header& header) {
  std::vector<uint32_t> layers = {0};
  for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
    const std::string name = it.name();
    const std::string prefix = "splat", suffix = ".R.hi";
    if (name.size() <= prefix.size() + suffix.size() || name.compare(0, prefix.size(), prefix) != 0 ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
      continue;
    const std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
    if (digits.empty() || digits.size() > 4 || digits.find_first_not_of("0123456789") != std::string::npos ||
        digits[0] == '0')
      fail(path, "unexpected channel " + name);
    layers.push_back(uint32_t(std::stoul(digits)));
  }
  std::sort(layers.begin(), layers.end());
  return layers;
}

const double* fieldData(const Film& film, const DoubleField& f) {
  static_assert(sizeof(RGBd) == 3 * sizeof(double));
  if (f.layer == -2) return reinterpret_cast<const double*>(film.pixelSums().data());
  if (f.layer == -1) return film.pixelCounts().data();
  return reinterpret_cast<const double*>(film.splatLayer(size_t(f.layer)).data());
}

// SHA-256 (hex) over "WxH nonFinite", then per field its name, '\0', its hi and lo words (little-endian).
std::string sumsChecksum(int width, int height, uint64_t nonFinite, const std::vector<DoubleField>& fields,
                         const std::vector<std::vector<uint32_t>>& words) {
  Sha256 sha;
  sha.update(std::to_string(width) + "x" + std::to_string(height) + " " + std::to_string(nonFinite));
  std::vector<uint8_t> bytes;
  for (size_t f = 0; f < fields.size(); ++f) {
    sha.update(fields[f].name + '\0');
    for (int half = 0; half < 2; ++half) {
      const std::vector<uint32_t>& w = words[2 * f + half];
      bytes.resize(4 * w.size());
      for (size_t i = 0; i < w.size(); ++i)
        for (int b = 0; b < 4; ++b) bytes[4 * i + b] = uint8_t(w[i] >> (8 * b));
      sha.update(bytes.data(), bytes.size());
    }
  }
  return sha.hexDigest();
}

}  // namespace

void writeFilmExr(const std::string& path, const Film& film, const ImageMetadata& metadata,
                  double previewSplatScale) {
  if (film.width() <= 0 || film.height() <= 0) fail(path, "cannot write an empty film");
  writeFilmExr(path, film, metadata, film.develop(previewSplatScale));
}

void writeFilmExr(const std::string& path, const Film& film, const ImageMetadata& metadata,
                  const std::vector<Color>& preview) {
  const int width = film.width(), height = film.height();
  if (width <= 0 || height <= 0) fail(path, "cannot write an empty film");
  const size_t n = film.pixelCount();
  Imf::Header header(width, height);
  header.compression() = Imf::ZIP_COMPRESSION;
  addMetadata(path, header, metadata);
  header.insert(kFormatAttr, Imf::StringAttribute(kPartialFilmFormat));
  header.insert(kFormatVersionAttr, Imf::IntAttribute(kPartialFilmVersion));
  header.insert(kNonFiniteAttr, Imf::DoubleAttribute(double(film.nonFiniteSamples())));

  if (preview.size() != n) fail(path, "preview has " + std::to_string(preview.size()) + " pixels, the film " + std::to_string(n));
  Imf::FrameBuffer fb;
  writeFloatRgb(header, fb, preview, width);

  // hi/lo words of every double, one plane per channel.
  const std::vector<DoubleField> fields = filmFields(film.splatLayers());
  std::vector<std::vector<uint32_t>> words(2 * fields.size(), std::vector<uint32_t>(n));
  for (size_t f = 0; f < fields.size(); ++f) {
    const double* data = fieldData(film, fields[f]);
    for (size_t i = 0; i < n; ++i) {
      const uint64_t bits = std::bit_cast<uint64_t>(data[i * fields[f].stride + fields[f].offset]);
      words[2 * f][i] = uint32_t(bits >> 32);
      words[2 * f + 1][i] = uint32_t(bits);
    }
    for (int half = 0; half < 2; ++half) {
      const std::string name = fields[f].name + (half == 0 ? ".hi" : ".lo");
      header.channels().insert(name, Imf::Channel(Imf::UINT));
      fb.insert(name, Imf::Slice(Imf::UINT, reinterpret_cast<char*>(words[2 * f + half].data()),
                                 sizeof(uint32_t), sizeof(uint32_t) * size_t(width)));
    }
  }
  header.insert(kSumsChecksumAttr,
                Imf::StringAttribute(sumsChecksum(width, height, film.nonFiniteSamples(), fields, words)));
  writeFrame(path, header, fb, height);
}

bool isFilmExr(const std::string& path) {
  try {
    checkReadable(path);
    Imf::InputFile file(path.c_str());
    const auto* a = file.header().findTypedAttribute<Imf::StringAttribute>(kFormatAttr);
    return a && a->value() == kPartialFilmFormat;
  } catch (const std::exception&) {
    return false;
  }
}

FilmExr readFilmExr(const std::string& path, const std::function<void(const FilmExrHeader&)>& check) {
  checkReadable(path);
  try {
    Imf::InputFile file(path.c_str());
    const Imf::Header& header = file.header();
    const auto* format = header.findTypedAttribute<Imf::StringAttribute>(kFormatAttr);
    if (!format || format->value() != kPartialFilmFormat)
      fail(path, "not a partial film EXR (missing header attribute mltfarm.format = partial-film)");
    const auto* version = header.findTypedAttribute<Imf::IntAttribute>(kFormatVersionAttr);
    if (!version || version->value() != kPartialFilmVersion)
      fail(path, "unsupported partial film format version (expected " + std::to_string(kPartialFilmVersion) + ")");
    const Size s = imageSize(path, header);
    if (header.displayWindow() != s.dw)
      fail(path, "size mismatch: data window differs from display window");

    const auto* checksum = header.findTypedAttribute<Imf::StringAttribute>(kSumsChecksumAttr);
    const auto* nfAttr = header.findTypedAttribute<Imf::DoubleAttribute>(kNonFiniteAttr);
    const double nf = nfAttr ? nfAttr->value() : 0.0;
    if (!(nf >= 0 && nf <= 9007199254740992.0) || nf != std::floor(nf)) fail(path, std::string("invalid ") + kNonFiniteAttr);
    const std::vector<uint32_t> layers = layersInHeader(path, header);
    if (check) check({s.width, s.height, layers, readMetadata(header, false)});  // before any allocation

    const size_t n = size_t(s.width) * size_t(s.height);
    const std::vector<DoubleField> fields = filmFields(layers);
    std::vector<std::vector<uint32_t>> words(2 * fields.size(), std::vector<uint32_t>(n));
    Imf::FrameBuffer fb;
    for (size_t f = 0; f < fields.size(); ++f) {
      for (int half = 0; half < 2; ++half) {
        const std::string name = fields[f].name + (half == 0 ? ".hi" : ".lo");
        const Imf::Channel* ch = header.channels().findChannel(name);
        if (!ch) fail(path, "missing channel " + name);
        if (ch->type != Imf::UINT) fail(path, "channel " + name + " is not of type UINT");
        if (ch->xSampling != 1 || ch->ySampling != 1) fail(path, "channel " + name + " is subsampled");
        fb.insert(name, Imf::Slice(Imf::UINT, slicesBase(words[2 * f + half].data(), s, sizeof(uint32_t)),
                                   sizeof(uint32_t), sizeof(uint32_t) * size_t(s.width)));
      }
    }
    file.setFrameBuffer(fb);
    file.readPixels(s.dw.min.y, s.dw.max.y);
    if (checksum && sumsChecksum(s.width, s.height, uint64_t(nf), fields, words) != checksum->value())
      fail(path, "the raw sums do not match their checksum (the file was rewritten, e.g. through float, or is corrupt)");

    FilmExr out{Film(s.width, s.height), readMetadata(header, false), checksum != nullptr};
    for (size_t f = 0; f < fields.size(); ++f) {
      if (fields[f].layer == -1) {  // the pixel counts, a plain vector
        double* data = out.film.pixelCounts().data();
        for (size_t i = 0; i < n; ++i)
          data[i] = std::bit_cast<double>((uint64_t(words[2 * f][i]) << 32) | words[2 * f + 1][i]);
        continue;
      }
      // The film is zero already: only the non-zero words are written, through writeBlock, so the blocks
      // the file holds no value in stay unmarked and are never read again (pixel_buffer.h).
      PixelBuffer& buffer = fields[f].layer == -2 ? out.film.pixelSums() : out.film.splatLayer(size_t(fields[f].layer));
      for (size_t i = 0; i < n; ++i) {
        const uint64_t bits = (uint64_t(words[2 * f][i]) << 32) | words[2 * f + 1][i];
        if (bits == 0) continue;
        RGBd& v = buffer.writeAt(i);
        reinterpret_cast<double*>(&v)[fields[f].offset] = std::bit_cast<double>(bits);
      }
    }
    out.film.setNonFiniteSamples(uint64_t(nf));
    return out;
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).rfind(path + ":", 0) == 0) throw;
    fail(path, std::string("cannot read EXR: ") + e.what());
  } catch (const std::exception& e) {
    fail(path, std::string("cannot read EXR: ") + e.what());
  }
}

}  // namespace mlt
