// A film buffer of n pixel values, all zero at first, whose memory comes from calloc: pages nothing ever
// writes are never faulted in, and nothing zeroes them twice. A Markov chain job's film holds a chain layer
// and a large-step layer per path length (mlt/develop.h); at 1920x1080 and depth 30 that is 60 layers of
// 50 MB, most of whose pixels the long lengths never reach. As std::vector<RGBd>, every layer was zeroed
// and faulted in whole: 2.6 GB resident and 65% of a one-mutation-per-pixel job (docs/PERFORMANCE.md).
// Small buffers are not worth it: a 256x256 layer (1.5 MB) faulted in page by page as the chains write it
// cost 4% of a depth-30 job against one memset (docs/PERFORMANCE.md), so below kCallocBytes the memory is
// malloc'd and zeroed at once, as std::vector did.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <span>
#include <type_traits>

namespace mlt {

template <class T>
class ZeroedBuffer {
  static_assert(std::is_trivially_copyable_v<T>, "ZeroedBuffer holds values whose zero bits are zero");

 public:
  ZeroedBuffer() = default;
  explicit ZeroedBuffer(size_t n) : data_(allocate(n)), size_(n) {}
  ZeroedBuffer(const ZeroedBuffer& o) : data_(allocate(o.size_)), size_(o.size_) {
    if (size_ > 0) std::memcpy(data_, o.data_, size_ * sizeof(T));
  }
  ZeroedBuffer(ZeroedBuffer&& o) noexcept : data_(o.data_), size_(o.size_) {
    o.data_ = nullptr;
    o.size_ = 0;
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
      o.data_ = nullptr;
      o.size_ = 0;
    }
    return *this;
  }
  ~ZeroedBuffer() { std::free(data_); }

  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  T* data() { return data_; }
  const T* data() const { return data_; }
  T& operator[](size_t i) { return data_[i]; }
  const T& operator[](size_t i) const { return data_[i]; }
  T* begin() { return data_; }
  T* end() { return data_ + size_; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }
  operator std::span<T>() { return {data_, size_}; }
  operator std::span<const T>() const { return {data_, size_}; }

 private:
  static constexpr size_t kCallocBytes = size_t{4} << 20;

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
};

}  // namespace mlt
