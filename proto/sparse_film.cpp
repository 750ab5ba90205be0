// Zero-run film encoding (see sparse_film.h).
#include "proto/sparse_film.h"

#include <algorithm>
#include <cstring>
#include <fmt/format.h>

#include "proto/convert.h"

namespace mlt::wire {
namespace {

// The film's buffers in the dense order of encodeFilm, as runs of 8-byte words.
struct Segment {
  const uint64_t* data;
  size_t words;
  const PixelBuffer* buffer = nullptr;  // its blocks (pixel_buffer.h); nullptr: the pixel counts
};
std::vector<Segment> segments(const Film& film) {
  const size_t n = film.pixelCount();
  std::vector<Segment> s;
  auto add = [&](const PixelBuffer& b) { s.push_back({reinterpret_cast<const uint64_t*>(b.data()), 3 * n, &b}); };
  add(film.pixelSums());
  s.push_back({reinterpret_cast<const uint64_t*>(film.pixelCounts().data()), n});
  for (uint32_t l : film.splatLayers()) add(film.splatLayer(l));
  return s;
}
constexpr size_t kBlockWords = 3 * PixelBuffer::kBlock;

void putVarint(std::string& out, uint64_t v) {
  while (v >= 0x80) {
    out += char(uint8_t(v) | 0x80);
    v >>= 7;
  }
  out += char(uint8_t(v));
}

uint64_t getVarint(const std::string& in, size_t& pos) {
  uint64_t v = 0;
  for (int shift = 0; shift < 64; shift += 7) {
    if (pos >= in.size()) throw WireError("film_chunk", "zero-run stream ends inside a run length");
    const uint8_t b = uint8_t(in[pos++]);
    v |= uint64_t(b & 0x7f) << shift;
    if (!(b & 0x80)) return v;
  }
  throw WireError("film_chunk", "zero-run length too long");
}

}  // namespace

size_t maxZeroRunsBytes(int width, int height, size_t splatLayers) {
  // Literal words cost 8 bytes as in the dense layout; each run pair costs at most 20 bytes of varints but
  // a pair needs a zero word (saving 8) except the last, so the stream never exceeds dense + 20.
  return filmByteSize(width, height, splatLayers) + 20;
}

std::string encodeFilmZeroRuns(const Film& film) {
  static_assert(sizeof(RGBd) == 3 * sizeof(double) && sizeof(double) == sizeof(uint64_t));
  std::string out;
  out.reserve(1024);
  // Runs may cross buffer boundaries: walk the buffers as one word sequence.
  const std::vector<Segment> segs = segments(film);
  size_t seg = 0, i = 0;
  auto atEnd = [&] {
    while (seg < segs.size() && i == segs[seg].words) {
      ++seg;
      i = 0;
    }
    return seg == segs.size();
  };
  while (!atEnd()) {
    uint64_t zeros = 0;
    while (!atEnd()) {
      const Segment& g = segs[seg];
      // A block nothing wrote is zero: counted without reading it (and faulting in its pages).
      if (g.buffer && i % kBlockWords == 0 && !g.buffer->blockWritten(i / kBlockWords)) {
        const size_t k = std::min(kBlockWords, g.words - i);
        zeros += k;
        i += k;
        continue;
      }
      if (g.data[i] != 0) break;
      ++zeros;
      ++i;
    }
    // Literal words: up to the next zero word. Recorded as positions, copied after the length is known.
    std::vector<Segment> literal;
    uint64_t count = 0;
    while (!atEnd() && segs[seg].data[i] != 0) {
      const size_t start = i;
      while (i < segs[seg].words && segs[seg].data[i] != 0) ++i;
      literal.push_back({segs[seg].data + start, i - start});
      count += i - start;
    }
    putVarint(out, zeros);
    putVarint(out, count);
    for (const Segment& l : literal) out.append(reinterpret_cast<const char*>(l.data), l.words * 8);
  }
  return out;
}

Film decodeFilmZeroRuns(int width, int height, const std::string& bytes, uint64_t nonFinite,
                        const std::vector<uint32_t>& layers) {
  // A zero film checked as the dense decoder checks it, filled in place: the zero runs cost nothing.
  Film film = zeroFilm(width, height, nonFinite, layers);
  // The pixel-sum and splat buffers are written through writeRange, which marks the blocks the literal
  // words reach (pixel_buffer.h): the blocks a zero run covers stay unmarked and are never read again.
  std::vector<PixelBuffer*> pixelBufs;  // nullptr: the pixel counts (a plain vector)
  std::vector<size_t> sizes;
  const size_t n = film.pixelCount();
  pixelBufs.push_back(&film.pixelSums());
  sizes.push_back(3 * n);
  pixelBufs.push_back(nullptr);
  sizes.push_back(n);
  for (uint32_t l : layers) {
    pixelBufs.push_back(&film.splatLayer(l));
    sizes.push_back(3 * n);
  }
  // Words [i, i + k) of buffer seg, ready for writing.
  auto target = [&](size_t seg, size_t i, size_t k) -> uint64_t* {
    if (!pixelBufs[seg]) return reinterpret_cast<uint64_t*>(film.pixelCounts().data()) + i;
    const size_t first = i / 3, last = (i + k - 1) / 3;
    RGBd* p = pixelBufs[seg]->writeRange(first, last - first + 1);
    return reinterpret_cast<uint64_t*>(p) + (i - 3 * first);
  };
  const size_t nBufs = sizes.size();
  size_t seg = 0, i = 0, pos = 0;
  auto skip = [&](uint64_t words) {
    while (words > 0) {
      if (seg == nBufs) throw WireError("film_chunk", "zero-run stream longer than the film");
      const uint64_t k = std::min<uint64_t>(words, sizes[seg] - i);
      i += k;
      words -= k;
      if (i == sizes[seg]) {
        ++seg;
        i = 0;
      }
    }
  };
  while (pos < bytes.size()) {
    skip(getVarint(bytes, pos));  // the film is zero already
    uint64_t literal = getVarint(bytes, pos);
    if (literal > (bytes.size() - pos) / 8) throw WireError("film_chunk", "zero-run stream ends inside literal words");
    while (literal > 0) {
      if (seg == nBufs) throw WireError("film_chunk", "zero-run stream longer than the film");
      const uint64_t k = std::min<uint64_t>(literal, sizes[seg] - i);
      std::memcpy(target(seg, i, k), bytes.data() + pos, k * 8);
      pos += k * 8;
      literal -= k;
      skip(k);
    }
  }
  if (seg != nBufs)
    throw WireError("film_chunk", fmt::format("zero-run stream covers {} buffers of {}", seg, nBufs));
  return film;
}

}  // namespace mlt::wire
