// Zero-run film encoding (see sparse_film.h).
#include "proto/sparse_film.h"

#include <cstring>
#include <fmt/format.h>

#include "proto/convert.h"

namespace mlt::wire {
namespace {

// The film's buffers in the dense order of encodeFilm, as runs of 8-byte words.
struct Segment {
  const uint64_t* data;
  size_t words;
};
std::vector<Segment> segments(const Film& film) {
  const size_t n = film.pixelCount();
  std::vector<Segment> s;
  s.push_back({reinterpret_cast<const uint64_t*>(film.pixelSums().data()), 3 * n});
  s.push_back({reinterpret_cast<const uint64_t*>(film.pixelCounts().data()), n});
  for (uint32_t l : film.splatLayers()) s.push_back({reinterpret_cast<const uint64_t*>(film.splatLayer(l).data()), 3 * n});
  return s;
}

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
    while (!atEnd() && segs[seg].data[i] == 0) {
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
  std::vector<uint64_t*> bufs;
  std::vector<size_t> sizes;
  const size_t n = film.pixelCount();
  bufs.push_back(reinterpret_cast<uint64_t*>(film.pixelSums().data()));
  sizes.push_back(3 * n);
  bufs.push_back(reinterpret_cast<uint64_t*>(film.pixelCounts().data()));
  sizes.push_back(n);
  for (uint32_t l : layers) {
    bufs.push_back(reinterpret_cast<uint64_t*>(film.splatLayer(l).data()));
    sizes.push_back(3 * n);
  }
  size_t seg = 0, i = 0, pos = 0;
  auto skip = [&](uint64_t words) {
    while (words > 0) {
      if (seg == bufs.size()) throw WireError("film_chunk", "zero-run stream longer than the film");
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
      if (seg == bufs.size()) throw WireError("film_chunk", "zero-run stream longer than the film");
      const uint64_t k = std::min<uint64_t>(literal, sizes[seg] - i);
      std::memcpy(bufs[seg] + i, bytes.data() + pos, k * 8);
      pos += k * 8;
      literal -= k;
      skip(k);
    }
  }
  if (seg != bufs.size())
    throw WireError("film_chunk", fmt::format("zero-run stream covers {} buffers of {}", seg, bufs.size()));
  return film;
}

}  // namespace mlt::wire
