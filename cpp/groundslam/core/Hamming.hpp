#pragma once
#include <cstdint>
#include <cstring>

namespace groundslam {

/// Hamming distance of two 256-bit (32-byte) binary descriptors such as ORB's.
inline int hammingDistance256(const std::uint8_t* a, const std::uint8_t* b) {
  int distance = 0;
  for (int i = 0; i < 32; i += 8) {
    std::uint64_t x, y;
    std::memcpy(&x, a + i, 8);
    std::memcpy(&y, b + i, 8);
    distance += __builtin_popcountll(x ^ y);
  }
  return distance;
}

}  // namespace groundslam
