// One work unit's splats, kept sparse until they are added to a film.
//
// A Markov chain of M mutations splats into a few thousand of a film's pixels (the default job's chains:
// 16384 mutations each on a 256x256 film). A dense Film per chain cost 5 MiB of zeroed buffers that were
// then scanned whole twice, by quantizeFilm and by the in-order merge: about 7% of mmlt's time in the
// default job, and on a worker, where task threads come and go, page faults on top. SparseSplatter
// accumulates into a dense scratch layer owned by the thread (allocated once, kept zero between units)
// while listing the pixels it touches; take() hands out only those, in ascending pixel order.
//
// Bit-identical to the dense path: every splat is added to its pixel in the same order (Film::addSplat's
// rules: non-finite values are counted and dropped, off-film splats ignored), and adding the listed
// values into a film gives the film the dense unit film's merge would, since the pixels not listed hold
// exact zeros there.
#pragma once
#include <cstdint>
#include <vector>

#include "common/core/color.h"
#include "common/core/vec.h"
#include "common/film/film.h"

namespace mlt {

// The splats of one unit into film layers: for each layer, ascending pixel indices and their sums.
struct SparseSplats {
  struct Layer {
    uint32_t layer = 0;
    std::vector<uint32_t> index;  // ascending, each once
    std::vector<RGBd> value;      // value[j] is the sum at pixel index[j]
  };
  int width = 0, height = 0;      // of the film the splats belong to; 0 x 0: no splats at all
  std::vector<Layer> layers;      // ascending layer numbers, each once; a layer may list no pixel
  uint64_t nonFinite = 0;         // splats dropped as non-finite

  bool empty() const { return width == 0 && height == 0; }
  // film += these splats: an empty (0 x 0) film first becomes a zero film of their size; allocates every
  // listed layer (even one without pixels, as a dense unit film had it) and adds nonFinite. Throws
  // std::invalid_argument if the film's size differs.
  void addTo(Film& film) const;
};

// Accumulates one unit's splats into one layer of a width x height film.
class SparseSplatter {
 public:
  SparseSplatter(int width, int height, uint32_t layer);
  ~SparseSplatter();
  SparseSplatter(const SparseSplatter&) = delete;
  SparseSplatter& operator=(const SparseSplatter&) = delete;
  int width() const { return width_; }
  int height() const { return height_; }

  // As Film::addSplat into this layer. The add itself is deferred by kDelay splats (first in, first out,
  // so every pixel still receives its splats in the same order: the same bits): a chain's splat lands on a
  // pixel the scratch layer (24 bytes a pixel, 1.5 MiB at 256x256) rarely holds in cache after a large
  // step, and the load missed on ~70% of this function's time. Prefetched now, the pixel is in cache
  // kDelay splats (about as many mutations) later, when it is added.
  void addSplat(Vec2 pRaster, const Color& v) {
    if (!v.isFinite()) {
      ++nonFinite_;
      return;
    }
    const long i = filmPixelIndex(pRaster, width_, height_);
    if (i < 0) return;
    __builtin_prefetch(&dense_[size_t(i)], 1);
    __builtin_prefetch(reinterpret_cast<const char*>(&dense_[size_t(i)]) + sizeof(RGBd) - 1, 1);
    __builtin_prefetch(&touched_[size_t(i)], 1);
    Pending& slot = pending_[nQueued_ % kDelay];
    if (nQueued_ >= kDelay) apply(slot.pixel, slot.v);
    slot = {uint32_t(i), v};
    ++nQueued_;
  }
  // Adds v to pixel `pixel` (< width * height) as it stands: exact doubles, no finiteness rule (the b
  // strata of develop.h (D6): a count and sums of a bounded value). After the deferred splats.
  void addAt(size_t pixel, const RGBd& v) {
    flush();
    touch(pixel);
    dense_[pixel] += v;
  }
  // The splats so far (one layer, pixels ascending); the scratch is zero again and the splatter empty.
  SparseSplats take();

 private:
  static constexpr uint64_t kDelay = 8;  // a power of two
  struct Pending {
    uint32_t pixel;
    Color v;
  };
  void touch(size_t pixel) {
    if (!touched_[pixel]) {
      touched_[pixel] = 1;
      list_->push_back(uint32_t(pixel));
    }
  }
  void apply(uint32_t pixel, const Color& v) {
    touch(pixel);
    dense_[pixel].add(v);
  }
  void flush();         // applies the deferred splats, oldest first
  void sortedList();    // the list in ascending order
  void clearScratch();  // the listed pixels back to zero, the list empty
  int width_, height_;
  uint32_t layer_;
  uint64_t nonFinite_ = 0;
  struct Scratch;
  Scratch* scratch_;  // one of the thread's scratches, or one of its own if all are in use
  bool owned_;
  RGBd* dense_;
  uint8_t* touched_;
  std::vector<uint32_t>* list_;
  Pending pending_[kDelay];
  uint64_t nQueued_ = 0;  // splats queued since the last flush; the last min(nQueued_, kDelay) are pending
};

}  // namespace mlt
