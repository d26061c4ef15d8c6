#pragma once
// Helpers of groundslam's binary files (vocabulary, map): little-endian values, an FNV-1a checksum of
// everything before it, and a reader that fails with the file's name when the bytes run out.

#include <cstdint>
#include <cstring>
#include <string>

#include "groundslam/io/InputError.hpp"

namespace groundslam {

inline std::uint64_t fnv1a(const std::string& bytes, size_t length) {
  std::uint64_t hash = 1469598103934665603ULL;
  for (size_t i = 0; i < length; ++i) {
    hash ^= static_cast<unsigned char>(bytes[i]);
    hash *= 1099511628211ULL;
  }
  return hash;
}

template <class T>
void putValue(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

/// Appends the checksum of everything written so far.
inline void putChecksum(std::string& out) { putValue(out, fnv1a(out, out.size())); }

/// True when the last 8 bytes are the checksum of the rest.
inline bool checksumMatches(const std::string& bytes) {
  if (bytes.size() < 8) return false;
  std::uint64_t stored;
  std::memcpy(&stored, bytes.data() + bytes.size() - 8, 8);
  return stored == fnv1a(bytes, bytes.size() - 8);
}

/// Reads fixed-size values from a byte string, failing with the file's name when it runs out.
class BinaryReader {
 public:
  BinaryReader(const std::string& bytes, const std::string& path, const char* what) : bytes_(bytes), path_(path), what_(what) {}
  template <class T>
  T get() {
    T value;
    if (offset_ + sizeof(T) > bytes_.size()) throw InputError(path_ + ": " + what_ + " file is truncated");
    std::memcpy(&value, bytes_.data() + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  void skip(size_t n) { offset_ += n; }
  size_t offset() const { return offset_; }

 private:
  const std::string& bytes_;
  const std::string& path_;
  const char* what_;
  size_t offset_ = 0;
};

}  // namespace groundslam
