// SHA-256 (FIPS 180-4), incremental. Used to content-address scene bundles.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace mlt {

class Sha256 {
 public:
  Sha256();
  void update(const void* data, size_t size);
  void update(const std::string& s) { update(s.data(), s.size()); }
  // Finishes the hash; the object must not be updated afterwards.
  std::array<uint8_t, 32> digest();
  std::string hexDigest();  // 64 lowercase hex digits

 private:
  void block(const uint8_t* p);
  uint32_t h_[8];
  uint8_t buf_[64];
  size_t bufLen_ = 0;
  uint64_t totalBytes_ = 0;
};

std::string sha256Hex(const std::string& data);
// Hashes a file's bytes; throws std::runtime_error naming the file if it cannot be read.
std::string sha256File(const std::string& path);

}  // namespace mlt
