// Sparse splats of one work unit (see sparse_splats.h).
#include "common/film/sparse_splats.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <stdexcept>
#include <string>

namespace mlt {

void SparseSplats::addTo(Film& film) const {
  if (empty()) return;
  if (film.pixelCount() == 0) film = Film(width, height);
  if (film.width() != width || film.height() != height)
    throw std::invalid_argument("SparseSplats::addTo: film size mismatch " + std::to_string(film.width()) + "x" +
                                std::to_string(film.height()) + " vs " + std::to_string(width) + "x" +
                                std::to_string(height));
  for (const Layer& l : layers) {
    PixelBuffer& buffer = film.splatLayer(l.layer);
    // writeAt: a block's first write faults its pages in once (pixel_buffer.h).
    for (size_t j = 0; j < l.index.size(); ++j) {
      const uint32_t i = l.index[j];
      buffer.writeAt(i) += l.value[j];
    }
  }
  film.setNonFiniteSamples(film.nonFiniteSamples() + nonFinite);
}

// A dense layer kept zero between units, a byte per pixel marking the touched ones, and their list.
struct SparseSplatter::Scratch {
  std::vector<RGBd> dense;
  std::vector<uint8_t> touched;
  std::vector<uint32_t> list;
  bool inUse = false;
  void fit(size_t pixels) {
    if (dense.size() == pixels) return;
    dense.assign(pixels, RGBd{});
    touched.assign(pixels, 0);
    list.clear();
  }
};

SparseSplatter::SparseSplatter(int width, int height, uint32_t layer) : width_(width), height_(height), layer_(layer) {
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("SparseSplatter: film size must be positive, got " + std::to_string(width) + "x" +
                                std::to_string(height));
  // Scratches per thread, reused unit after unit: a chain unit holds up to three splatters at once (its
  // splats, its b strata, mlt/develop.h (D6), and veach-mlt's light views or Kelemen MIS's large steps,
  // (D7)); a further one alive on the same thread (a test) gets its own.
  static thread_local Scratch threadScratch[3];
  Scratch* free = nullptr;
  for (Scratch& s : threadScratch)
    if (!s.inUse) {
      free = &s;
      break;
    }
  owned_ = free == nullptr;
  scratch_ = owned_ ? new Scratch : free;
  scratch_->inUse = true;
  scratch_->fit(size_t(width) * size_t(height));
  dense_ = scratch_->dense.data();
  touched_ = scratch_->touched.data();
  list_ = &scratch_->list;
  list_->clear();
}

void SparseSplatter::flush() {
  const uint64_t first = nQueued_ > kDelay ? nQueued_ - kDelay : 0;
  for (uint64_t q = first; q < nQueued_; ++q) apply(pending_[q % kDelay].pixel, pending_[q % kDelay].v);
  nQueued_ = 0;
}

// Ascending pixel order. A chain unit touches thousands of pixels: reading the touched bytes eight at a
// time (a 256x256 film: 8192 words) costs a few microseconds where sorting the list cost a few hundred
// (2.3% of an mmlt job's time); a short list is sorted.
void SparseSplatter::sortedList() {
  std::vector<uint32_t>& list = *list_;
  const size_t pixels = size_t(width_) * size_t(height_);
  if (list.size() < pixels / 256) {
    std::sort(list.begin(), list.end());
    return;
  }
  static_assert(std::endian::native == std::endian::little, "the word scan reads byte j as bits 8j..8j+7");
  const size_t n = list.size();
  list.clear();
  size_t i = 0;
  for (; i + 8 <= pixels; i += 8) {
    uint64_t word;
    std::memcpy(&word, touched_ + i, 8);
    while (word) {  // each byte is 0 or 1: bit 8 j set <=> pixel i + j touched (little-endian)
      list.push_back(uint32_t(i + size_t(std::countr_zero(word)) / 8));
      word &= word - 1;
    }
  }
  for (; i < pixels; ++i)
    if (touched_[i]) list.push_back(uint32_t(i));
  if (list.size() != n) throw std::logic_error("SparseSplatter: touched bytes and the touched list disagree");
}

void SparseSplatter::clearScratch() {
  for (uint32_t i : *list_) {
    dense_[i] = RGBd{};
    touched_[i] = 0;
  }
  list_->clear();
}

SparseSplatter::~SparseSplatter() {
  nQueued_ = 0;    // an abandoned unit's deferred splats were never added: nothing of theirs to clear
  clearScratch();  // zero for the next unit even if this one was abandoned (an exception in the chain)
  scratch_->inUse = false;
  if (owned_) delete scratch_;
}

SparseSplats SparseSplatter::take() {
  SparseSplats out;
  out.width = width_;
  out.height = height_;
  out.nonFinite = nonFinite_;
  SparseSplats::Layer& l = out.layers.emplace_back();
  l.layer = layer_;
  flush();
  sortedList();
  l.index = *list_;
  l.value.resize(l.index.size());
  for (size_t j = 0; j < l.index.size(); ++j) l.value[j] = dense_[l.index[j]];
  clearScratch();
  nonFinite_ = 0;
  return out;
}

}  // namespace mlt
