// A film buffer of n pixel values, all zero at first, whose memory comes from calloc: pages nothing ever
// writes are never faulted in, and nothing zeroes them twice. A Markov chain job's film holds a chain layer
// and a large-step layer per path length (mlt/develop.h); at 1920x1080 and depth 30 that is 60 layers of
// 50 MB, most of whose pixels the long lengths never reach. As std::vector<RGBd>, every layer was zeroed
// and faulted in whole: 2.6 GB resident and 65% of a one-mutation-per-pixel job (docs/PERFORMANCE.md).
// Small buffers are not worth it: a 256x256 layer (1.5 MB) faulted in page by page as the chains write it
// cost 4% of a depth-30 job against one memset (docs/PERFORMANCE.md), so below kCallocBytes the memory is
// malloc'd and zeroed at once, as std::vector did.
//
// Written blocks. The buffer also knows which blocks of kBlock values may be non-zero: every mutable
// access marks what it can reach (operator[] its value's block, data(), begin() and the span conversion
// all of them), so a block not marked is all zero, by construction. Readers that only need the non-zero
// values (Film::develop, merge, the partial-film codecs) skip the rest and never read, hence never fault
// in, pages nothing wrote. Threads may write disjoint values through operator[] at the same time (a
// sample job's tiles do): its mark is a relaxed atomic store, a plain byte store on x86. writeBlock and
// writeRange, whose first write zeroes the block, are for one writer at a time.
#pragma once
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <span>
#include <type_traits>
#include <vector>

namespace mlt {

template <class T>
class ZeroedBuffer {
  static_assert(std::is_trivially_copyable_v<T>, "ZeroedBuffer holds values whose zero bits are zero");

 public:
  static constexpr size_t kBlockShift = 7;
  static constexpr size_t kBlock = size_t{1} << kBlockShift;  // values per block (3 KB of RGBd: a first write faults in one or two pages)

  ZeroedBuffer() = default;
  explicit ZeroedBuffer(size_t n) : data_(allocate(n)), size_(n), written_((n + kBlock - 1) >> kBlockShift, 0) {}
  ZeroedBuffer(const ZeroedBuffer& o) : data_(allocate(o.size_)), size_(o.size_), written_(o.written_) {
    for (size_t b = 0; b < written_.size(); ++b)
      if (written_[b]) std::memcpy(data_ + b * kBlock, o.data_ + b * kBlock, blockSize(b) * sizeof(T));
  }
  ZeroedBuffer(ZeroedBuffer&& o) noexcept : data_(o.data_), size_(o.size_), written_(std::move(o.written_)) {
    o.data_ = nullptr;
    o.size_ = 0;
    o.written_.clear();
  }
  ZeroedBuffer& operator=(const ZeroedBuffer& o) {
    if (this != &o) *this = ZeroedBuffer(o);
    return *this;
  }
  ZeroedBuffer& operator=(ZeroedBuffer&& o) noexcept {
    if (this != &o) {
      std::free(data_);
      data_ = o.data_;
      size_ = o.size_;
      written_ = std::move(o.written_);
      o.data_ = nullptr;
      o.size_ = 0;
      o.written_.clear();
    }
    return *this;
  }
  ~ZeroedBuffer() { std::free(data_); }

  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

  // Mutable access marks the blocks it can reach; const access marks nothing.
  T& operator[](size_t i) {
    std::atomic_ref<uint8_t>(written_[i >> kBlockShift]).store(1, std::memory_order_relaxed);
    return data_[i];
  }
  const T& operator[](size_t i) const { return data_[i]; }
  T* data() { markAll(); return data_; }
  const T* data() const { return data_; }
  T* begin() { markAll(); return data_; }
  T* end() { return data_ + size_; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }
  operator std::span<T>() { markAll(); return {data_, size_}; }
  operator std::span<const T>() const { return {data_, size_}; }

  // ---- blocks --------------------------------------------------------------------------------------
  size_t blockCount() const { return written_.size(); }
  size_t blockSize(size_t b) const { return b + 1 < written_.size() ? kBlock : size_ - b * kBlock; }
  // False: every value of block b is zero. (True: some may not be.)
  bool blockWritten(size_t b) const { return written_[b] != 0; }
  const T* block(size_t b) const { return data_ + b * kBlock; }
  // Block b for writing, marked. A calloc'd block written for the first time is first zeroed by a write:
  // its pages then fault in once, writable, instead of mapping the kernel's zero page on the first
  // read of a `+=` and copying it on the write.
  T* writeBlock(size_t b) {
    T* p = data_ + b * kBlock;
    if (!written_[b]) {
      written_[b] = 1;
      if (size_ * sizeof(T) >= kCallocBytes) std::memset(static_cast<void*>(p), 0, blockSize(b) * sizeof(T));
    }
    return p;
  }
  // Value i for writing, its block marked (and zeroed on its first write) as writeBlock does: for one
  // writer at a time that reads the value before it writes (`+=`), unlike operator[].
  T& writeAt(size_t i) { return writeBlock(i >> kBlockShift)[i & (kBlock - 1)]; }
  // Values [first, first + count) for writing (a raw copy into them, e.g. a decoder), their blocks marked
  // as writeBlock marks them, before the caller writes.
  T* writeRange(size_t first, size_t count) {
    if (count > 0)
      for (size_t b = first >> kBlockShift; b <= (first + count - 1) >> kBlockShift; ++b) writeBlock(b);
    return data_ + first;
  }
  // f(b, values, count) for every written block b, in order.
  template <class F>
  void forEachWrittenBlock(F&& f) const {
    for (size_t b = 0; b < written_.size(); ++b)
      if (written_[b]) f(b, data_ + b * kBlock, blockSize(b));
  }

 private:
  static constexpr size_t kCallocBytes = size_t{4} << 20;

  void markAll() {
    if (!written_.empty()) std::memset(written_.data(), 1, written_.size());  // no memset on a null pointer
  }

  static T* allocate(size_t n) {
    if (n == 0) return nullptr;
    if (n > SIZE_MAX / sizeof(T)) throw std::bad_alloc();
    const size_t bytes = n * sizeof(T);
    if (bytes >= kCallocBytes) {
      void* p = std::calloc(n, sizeof(T));
      if (!p) throw std::bad_alloc();
      return static_cast<T*>(p);
    }
    void* p = std::malloc(bytes);
    if (!p) throw std::bad_alloc();
    // Without this barrier GCC folds malloc + memset into calloc, which is what this branch avoids.
    asm volatile("" : : "r"(p) : "memory");
    std::memset(p, 0, bytes);
    return static_cast<T*>(p);
  }
  T* data_ = nullptr;
  size_t size_ = 0;
  std::vector<uint8_t> written_;  // per block: 1 if a mutable access may have written it
};

}  // namespace mlt
