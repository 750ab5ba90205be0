// EXR and PNG I/O: developed images round-trip float-exactly with metadata; partial films round-trip
// bit-exactly (every double, including ones a float could not hold); clear errors naming the file.
#include "common/io/exr_io.h"
#include "common/io/png_io.h"

#include <gtest/gtest.h>

#include <cstring>
#include <png.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIntAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>

#include <functional>

#include <bit>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <vector>

#include "common/core/rng.h"

namespace mlt {
namespace {

std::string tempPath(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "mltfarm_exr_test";
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(Exr, DevelopedImageRoundTripIsFloatExact) {
  const int w = 17, h = 5;
  std::vector<Color> rgb(w * h);
  Pcg32 rng(7, 1);
  for (Color& c : rgb) c = Color(rng.uniform() * 1e4f, rng.uniform() * 1e-6f, rng.uniform() - 0.5f);
  ImageMetadata meta;
  meta.strings["method"] = "bdpt";
  meta.strings["sceneHash"] = "abc123";
  meta.numbers["spp"] = 64;
  meta.numbers["seed"] = 9007199254740992.0;  // 2^53: counts survive as doubles
  meta.numbers["b"] = 0.123456789012345678;
  const std::string path = tempPath("developed.exr");
  writeExr(path, w, h, rgb, meta);
  const ExrImage img = readExr(path);
  EXPECT_EQ(img.width, w);
  EXPECT_EQ(img.height, h);
  ASSERT_EQ(img.rgb.size(), rgb.size());
  for (size_t i = 0; i < rgb.size(); ++i)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(std::bit_cast<uint32_t>(img.rgb[i][c]), std::bit_cast<uint32_t>(rgb[i][c]));
  EXPECT_EQ(img.metadata, meta);
}

TEST(Exr, PartialFilmRoundTripIsBitExact) {
  Film film(9, 4);
  Pcg32 rng(11, 3);
  for (int i = 0; i < 500; ++i) {
    const Vec2 p(rng.uniform() * 9, rng.uniform() * 4);
    // Values that need every bit of a double once summed.
    film.addSample(p, Color(rng.uniform() * 1e-3f, rng.uniform() * 3.f, rng.uniform() * 1e5f));
    film.addSplat(Vec2(rng.uniform() * 9, rng.uniform() * 4), Color(rng.uniform() / 3.f));
  }
  film.addSample({1, 1}, Color(std::numeric_limits<float>::quiet_NaN()));
  film.pixelSums()[0].r = -0.0;
  film.splatSums()[1].g = std::numeric_limits<double>::denorm_min();
  film.splatSums()[2].b = 1.0 / 3.0;  // not representable as a float
  ImageMetadata meta;
  meta.strings["method"] = "pssmlt";
  meta.strings["chains"] = "3,5,8";
  meta.numbers["b"] = 1.0 / 7.0;
  meta.numbers["mutations"] = 123456789012.0;
  const std::string path = tempPath("partial.exr");
  writeFilmExr(path, film, meta, 0.5);
  ASSERT_TRUE(isFilmExr(path));
  const FilmExr back = readFilmExr(path);
  EXPECT_EQ(back.metadata, meta);
  ASSERT_EQ(back.film.width(), 9);
  ASSERT_EQ(back.film.height(), 4);
  EXPECT_EQ(back.film.nonFiniteSamples(), 1u);
  auto bits = [](double d) { return std::bit_cast<uint64_t>(d); };
  for (size_t i = 0; i < film.pixelCount(); ++i) {
    EXPECT_EQ(bits(back.film.pixelSums()[i].r), bits(film.pixelSums()[i].r)) << i;
    EXPECT_EQ(bits(back.film.pixelSums()[i].g), bits(film.pixelSums()[i].g)) << i;
    EXPECT_EQ(bits(back.film.pixelSums()[i].b), bits(film.pixelSums()[i].b)) << i;
    EXPECT_EQ(bits(back.film.pixelCounts()[i]), bits(film.pixelCounts()[i])) << i;
    EXPECT_EQ(bits(back.film.splatSums()[i].r), bits(film.splatSums()[i].r)) << i;
    EXPECT_EQ(bits(back.film.splatSums()[i].g), bits(film.splatSums()[i].g)) << i;
    EXPECT_EQ(bits(back.film.splatSums()[i].b), bits(film.splatSums()[i].b)) << i;
  }
  // The preview channels are the film developed with the given scale, readable as an ordinary EXR.
  const ExrImage preview = readExr(path);
  const std::vector<Color> expected = film.develop(0.5);
  ASSERT_EQ(preview.rgb.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(preview.rgb[i].g, expected[i].g);
}

TEST(Exr, PartialFilmKeepsEverySplatLayerBitExactly) {
  Film film(5, 3);
  Pcg32 rng(7, 1);
  for (int i = 0; i < 200; ++i)
    for (size_t layer : {size_t(0), size_t(2), size_t(31)})
      film.addSplat(Vec2(rng.uniform() * 5, rng.uniform() * 3), Color(rng.uniform() / 7.f), layer);
  const std::string path = tempPath("layers.exr");
  const std::vector<double> scales = {1, 0, 0.5, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
                                      0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.25};
  writeFilmExr(path, film, {}, film.develop(scales));
  const FilmExr back = readFilmExr(path);
  ASSERT_EQ(back.film.splatLayerCount(), 32u);
  for (size_t l = 0; l < 32; ++l) {
    ASSERT_EQ(back.film.hasSplatLayer(l), film.hasSplatLayer(l)) << l;
    if (!film.hasSplatLayer(l)) continue;
    EXPECT_EQ(std::memcmp(back.film.splatLayer(l).data(), film.splatLayer(l).data(), film.pixelCount() * sizeof(RGBd)), 0)
        << "layer " << l;
  }
  const std::vector<Color> a = film.develop(scales), b = back.film.develop(scales);
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(Color)), 0);
}

// Reading writes only the non-zero values, through writeBlock: the blocks the file holds nothing in stay
// unmarked (pixel_buffer.h) and develop reads the same image from fewer pages.
TEST(Exr, PartialFilmReadMarksOnlyTheBlocksItFills) {
  Film film(1000, 8);  // 8000 pixels: pixel i is in block i / kBlock
  film.addSplat({10.5f, 0.5f}, Color(1, 2, 3), 5);   // pixel 10
  film.addSplat({500.5f, 2.5f}, Color(0, 0, 4), 5);  // pixel 2500
  film.addSample({999.5f, 7.5f}, Color(1, 1, 1));    // the last pixel's sums, 7999
  const std::string path = tempPath("blocks.exr");
  const std::vector<double> scales = {1, 0, 0, 0, 0, 0.25};
  writeFilmExr(path, film, {}, film.develop(scales));
  const FilmExr back = readFilmExr(path);
  std::vector<size_t> l5, l0, pixels;
  back.film.splatLayer(5).forEachWrittenBlock([&](size_t b, const RGBd*, size_t) { l5.push_back(b); });
  back.film.splatLayer(0).forEachWrittenBlock([&](size_t b, const RGBd*, size_t) { l0.push_back(b); });
  back.film.pixelSums().forEachWrittenBlock([&](size_t b, const RGBd*, size_t) { pixels.push_back(b); });
  EXPECT_EQ(l5, (std::vector<size_t>{10 / PixelBuffer::kBlock, 2500 / PixelBuffer::kBlock}));
  EXPECT_TRUE(l0.empty());
  EXPECT_EQ(pixels, (std::vector<size_t>{7999 / PixelBuffer::kBlock}));
  const std::vector<Color> a = film.develop(scales), b = back.film.develop(scales);
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(Color)), 0);
}

TEST(Exr, ErrorsNameTheFile) {
  const std::string missing = tempPath("does_not_exist.exr");
  std::filesystem::remove(missing);
  std::string e = errorOf([&] { readExr(missing); });
  EXPECT_NE(e.find(missing), std::string::npos) << e;
  EXPECT_NE(e.find("no such file"), std::string::npos) << e;

  const std::string text = tempPath("not_an_exr.exr");
  std::ofstream(text) << "hello, I am not an image";
  e = errorOf([&] { readFilmExr(text); });
  EXPECT_NE(e.find(text), std::string::npos) << e;
  EXPECT_NE(e.find("not an OpenEXR file"), std::string::npos) << e;

  // A developed image is not a partial film.
  const std::string developed = tempPath("developed_only.exr");
  writeExr(developed, 2, 2, std::vector<Color>(4, Color(1)), {});
  EXPECT_FALSE(isFilmExr(developed));
  e = errorOf([&] { readFilmExr(developed); });
  EXPECT_NE(e.find(developed), std::string::npos) << e;
  EXPECT_NE(e.find("not a partial film"), std::string::npos) << e;

  // Size mismatch between pixels and dimensions; reserved metadata keys.
  e = errorOf([&] { writeExr(developed, 3, 2, std::vector<Color>(4), {}); });
  EXPECT_NE(e.find(developed), std::string::npos) << e;
  ImageMetadata reserved;
  reserved.strings["compression"] = "none";
  e = errorOf([&] { writeExr(developed, 2, 2, std::vector<Color>(4), reserved); });
  EXPECT_NE(e.find("reserved"), std::string::npos) << e;
}

// A damaged header: an attribute that declares 1.9 GB in a file of a few hundred bytes is refused before
// OpenEXR allocates it, in a single-part file and in one whose version field says multi-part; and so is a
// value whose declared size is not what OpenEXR's reader of its type takes (the fuzz test: a channel list
// lengthened by a mutation made OpenEXR read a later size from the bytes "\0\0co", 1.9 GB).
TEST(Exr, AHeaderOpenExrWouldMisreadIsRefusedBeforeItIsRead) {
  const std::string good = tempPath("header_good.exr");
  writeExr(good, 2, 2, std::vector<Color>(4, Color(1)), {});
  std::ifstream in(good, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Writes `damaged` as `name` and returns readExr's error (and the file's path).
  auto readDamaged = [&](const std::string& damaged, const std::string& name) {
    const std::string path = tempPath(name);
    std::ofstream(path, std::ios::binary | std::ios::trunc) << damaged;
    return std::make_pair(errorOf([&] { readExr(path); }), path);
  };
  // The 32-bit size field after an attribute's name\0type\0.
  auto setSize = [](std::string& b, const std::string& nameAndType, auto change) {
    const size_t at = b.find(nameAndType);
    if (at == std::string::npos) return false;
    uint32_t size = 0;
    std::memcpy(&size, &b[at + nameAndType.size()], 4);  // little-endian, as the file is
    size = change(size);
    std::memcpy(&b[at + nameAndType.size()], &size, 4);
    return true;
  };
  const std::string channels("channels\0chlist\0", 16);
  for (bool multiPart : {false, true}) {
    std::string damaged = bytes;
    ASSERT_TRUE(setSize(damaged, channels, [](uint32_t) { return 0x6f630000u; }));
    if (multiPart) damaged[5] = char(uint8_t(damaged[5]) | 0x10);
    const auto [e, path] = readDamaged(damaged, multiPart ? "header_multipart.exr" : "header_huge.exr");
    EXPECT_NE(e.find(path), std::string::npos) << e;
    EXPECT_NE(e.find("declares 1868759040 bytes"), std::string::npos) << multiPart << ": " << e;
    EXPECT_NE(errorOf([&] { readFilmExr(path); }).find("declares"), std::string::npos) << multiPart;
  }
  // A fixed-size value whose declared size is another (OpenEXR reads the type's size and would go on from
  // there): compression, 1 byte, declared 5.
  std::string fixed = bytes;
  ASSERT_TRUE(setSize(fixed, std::string("compression\0compression\0", 24), [](uint32_t) { return 5u; }));
  std::string e = readDamaged(fixed, "header_fixed.exr").first;
  EXPECT_NE(e.find("'compression' of type compression declares 5 bytes but its value takes 1"), std::string::npos) << e;
  // A channel list longer than it declares (a mutation that copied channel names past its end): the last
  // channel (a one-letter name, its terminator and 16 bytes) outside the declared size.
  std::string longer = bytes;
  ASSERT_TRUE(setSize(longer, channels, [](uint32_t size) { return size - 18; }));
  e = readDamaged(longer, "header_chlist.exr").first;
  EXPECT_NE(e.find("'channels' of type chlist declares"), std::string::npos) << e;
  // A real multi-part list that never ends (the bit set on a single-part file whose header is followed by
  // its offset table) is refused with a clear error or read as OpenEXR reads it, never by a huge allocation.
  std::string flipped = bytes;
  flipped[5] = char(uint8_t(flipped[5]) | 0x10);
  EXPECT_NE(readDamaged(flipped, "header_flipped.exr").first, "");
}

TEST(Exr, MissingOrBadChannelIsReported) {
  // Hand-made files that carry the partial-film tag but lack a raw channel or have a wrong type.
  auto writeTagged = [](const std::string& path, Imf::PixelType countLoType, bool withCountLo) {
    Imf::Header header(2, 2);
    header.insert("mltfarm.format", Imf::StringAttribute("partial-film"));
    header.insert("mltfarm.formatVersion", Imf::IntAttribute(1));
    std::vector<uint32_t> zeros(4, 0);
    Imf::FrameBuffer fb;
    for (const char* base : {"pixel.R", "pixel.G", "pixel.B", "count", "splat.R", "splat.G", "splat.B"}) {
      for (const char* half : {".hi", ".lo"}) {
        const std::string name = std::string(base) + half;
        Imf::PixelType type = Imf::UINT;
        if (name == "count.lo") {
          if (!withCountLo) continue;
          type = countLoType;
        }
        header.channels().insert(name, Imf::Channel(type));
        fb.insert(name, Imf::Slice(type, reinterpret_cast<char*>(zeros.data()), 4, 8));  // 0 bits = 0.0f too
      }
    }
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(2);
  };
  const std::string good = tempPath("tagged_good.exr");
  writeTagged(good, Imf::UINT, true);
  EXPECT_NO_THROW(readFilmExr(good));

  const std::string missing = tempPath("tagged_missing.exr");
  writeTagged(missing, Imf::UINT, false);
  std::string e = errorOf([&] { readFilmExr(missing); });
  EXPECT_NE(e.find(missing), std::string::npos) << e;
  EXPECT_NE(e.find("missing channel count.lo"), std::string::npos) << e;

  const std::string wrongType = tempPath("tagged_float.exr");
  writeTagged(wrongType, Imf::FLOAT, true);
  e = errorOf([&] { readFilmExr(wrongType); });
  EXPECT_NE(e.find("count.lo is not of type UINT"), std::string::npos) << e;

  // A truncated file gives a clean error naming the file, not a crash.
  Film film(64, 64);
  film.addSplat({3, 3}, Color(1));
  const std::string truncated = tempPath("partial_truncated.exr");
  writeFilmExr(truncated, film, {}, 1.0);
  std::filesystem::resize_file(truncated, std::filesystem::file_size(truncated) / 2);
  e = errorOf([&] { readFilmExr(truncated); });
  EXPECT_NE(e.find(truncated), std::string::npos) << e;
}

TEST(Png, WritesReadableFileOfTheRightSize) {
  const int w = 7, h = 3;
  std::vector<Color> rgb(w * h, Color(0.5f));
  rgb[0] = Color(std::numeric_limits<float>::quiet_NaN(), 2.0f, -1.0f);
  const std::string path = tempPath("preview.png");
  writePng(path, w, h, rgb, 0.f);

  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  ASSERT_TRUE(png_image_begin_read_from_file(&image, path.c_str())) << image.message;
  EXPECT_EQ(image.width, unsigned(w));
  EXPECT_EQ(image.height, unsigned(h));
  image.format = PNG_FORMAT_RGB;
  std::vector<uint8_t> pixels(PNG_IMAGE_SIZE(image));
  ASSERT_TRUE(png_image_finish_read(&image, nullptr, pixels.data(), 0, nullptr)) << image.message;
  EXPECT_EQ(pixels[0], 0);    // NaN -> 0
  EXPECT_EQ(pixels[1], 255);  // clamped
  EXPECT_EQ(pixels[2], 0);    // negative -> 0
  EXPECT_EQ(pixels[3], 188);  // sRGB(0.5) = 0.7354 -> 188
  // One stop of exposure doubles the linear value: 0.5 -> 1.0 -> 255.
  EXPECT_EQ(toSrgb8(0.5f, std::exp2(1.f)), 255);
  EXPECT_EQ(toSrgb8(0.0f, 1.f), 0);
}

}  // namespace
}  // namespace mlt
