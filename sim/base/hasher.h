// A 64-bit hash of a byte stream for cache keys (bind cache, automatic-cage cache) and file
// checksums: 8 bytes at a time, not cryptographic.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

namespace sb {

// A 64-bit hash of a byte stream, 8 bytes at a time (not cryptographic; a cache key).
class Hasher {
 public:
  explicit Hasher(std::uint64_t seed) : h_(seed ^ 0x9E3779B97F4A7C15ull) {}
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8) {
      std::uint64_t w;
      std::memcpy(&w, p + i, 8);
      mix(w);
    }
    std::uint64_t tail = 0;
    for (std::size_t k = 0; i < n; ++i, ++k) tail |= static_cast<std::uint64_t>(p[i]) << (8 * k);
    mix(tail ^ (static_cast<std::uint64_t>(n) << 56));
  }
  template <class T>
  void value(const T& v) {
    bytes(&v, sizeof(T));
  }
  std::uint64_t digest() const {
    std::uint64_t z = h_ + 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }

 private:
  void mix(std::uint64_t w) {
    w *= 0x87C37B91114253D5ull;
    w = (w << 31) | (w >> 33);
    w *= 0x4CF5AD432745937Full;
    h_ ^= w;
    h_ = ((h_ << 27) | (h_ >> 37)) * 5 + 0x52DCE729;
  }
  std::uint64_t h_;
};

// DIR/PREFIX<key as 32 hex digits>EXTENSION: the file a cache keeps under a 128-bit key.
inline std::string keyedCachePath(const std::string& dir, const std::string& prefix,
                                  const std::array<std::uint64_t, 2>& key,
                                  const std::string& extension) {
  char hex[40];
  std::snprintf(hex, sizeof(hex), "%016llx%016llx", static_cast<unsigned long long>(key[0]),
                static_cast<unsigned long long>(key[1]));
  std::string path = dir;
  if (!path.empty() && path.back() != '/') path += '/';
  return path + prefix + hex + extension;
}

}  // namespace sb
