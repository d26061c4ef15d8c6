#include "groundslam/io/VocabularyFile.hpp"

#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "groundslam/io/Files.hpp"
#include "groundslam/io/InputError.hpp"

namespace groundslam {
namespace {

constexpr char kMagic[8] = {'G', 'S', 'L', 'M', 'V', 'O', 'C', '\0'};

std::uint64_t fnv1a(const std::string& bytes, size_t length) {
  std::uint64_t hash = 1469598103934665603ULL;
  for (size_t i = 0; i < length; ++i) {
    hash ^= static_cast<unsigned char>(bytes[i]);
    hash *= 1099511628211ULL;
  }
  return hash;
}

template <class T>
void put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

/// Reads fixed-size values from a byte string, failing with the file's name when it runs out.
class Reader {
 public:
  Reader(const std::string& bytes, const std::string& path) : bytes_(bytes), path_(path) {}
  template <class T>
  T get() {
    T value;
    if (offset_ + sizeof(T) > bytes_.size()) throw InputError(path_ + ": vocabulary file is truncated");
    std::memcpy(&value, bytes_.data() + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  size_t offset() const { return offset_; }

 private:
  const std::string& bytes_;
  const std::string& path_;
  size_t offset_ = 0;
};

}  // namespace

void writeVocabulary(const std::string& path, const Vocabulary& vocabulary) {
  std::string out(kMagic, sizeof(kMagic));
  put(out, std::uint32_t{kVocabularyFormatVersion});
  put(out, static_cast<std::uint32_t>(vocabulary.branching()));
  put(out, static_cast<std::uint32_t>(vocabulary.depth()));
  put(out, static_cast<std::uint32_t>(vocabulary.nodes().size()));
  put(out, static_cast<std::uint32_t>(vocabulary.idf().size()));
  for (const auto& node : vocabulary.nodes()) {
    out.append(reinterpret_cast<const char*>(node.centre.data()), node.centre.size());
    put(out, std::int32_t{node.first_child});
    put(out, std::int32_t{node.child_count});
    put(out, std::int32_t{node.word});
  }
  for (double w : vocabulary.idf()) put(out, w);
  put(out, fnv1a(out, out.size()));
  writeFileAtomically(path, out);
}

Vocabulary readVocabulary(const std::string& path) { return parseVocabulary(readTextFile(path), path); }

Vocabulary parseVocabulary(const std::string& bytes, const std::string& path) {
  if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    throw InputError(path + ": not a groundslam vocabulary file (bad magic)");
  }
  Reader in(bytes, path);
  for (size_t i = 0; i < sizeof(kMagic); ++i) in.get<char>();
  const auto version = in.get<std::uint32_t>();
  if (version != kVocabularyFormatVersion) {
    throw InputError(path + ": vocabulary format version " + std::to_string(version) + ", this groundslam reads version " +
                     std::to_string(kVocabularyFormatVersion) + "; train it again with `groundslam vocabulary train`");
  }
  const auto branching = in.get<std::uint32_t>(), depth = in.get<std::uint32_t>();
  const auto node_count = in.get<std::uint32_t>(), word_count = in.get<std::uint32_t>();
  const size_t expected = in.offset() + size_t{node_count} * 44 + size_t{word_count} * 8 + 8;
  if (bytes.size() != expected) {
    throw InputError(path + ": vocabulary file is " + std::to_string(bytes.size()) + " bytes, its header promises " +
                     std::to_string(expected) + " (truncated or corrupt)");
  }
  std::uint64_t stored_checksum;
  std::memcpy(&stored_checksum, bytes.data() + bytes.size() - 8, 8);
  if (stored_checksum != fnv1a(bytes, bytes.size() - 8)) throw InputError(path + ": vocabulary file is corrupt (checksum)");
  std::vector<Vocabulary::Node> nodes(node_count);
  for (auto& node : nodes) {
    for (auto& byte : node.centre) byte = in.get<std::uint8_t>();
    node.first_child = in.get<std::int32_t>();
    node.child_count = in.get<std::int32_t>();
    node.word = in.get<std::int32_t>();
  }
  std::vector<double> idf(word_count);
  for (double& w : idf) w = in.get<double>();
  try {
    return Vocabulary(static_cast<int>(branching), static_cast<int>(depth), std::move(nodes), std::move(idf));
  } catch (const std::invalid_argument& e) {
    throw InputError(path + ": vocabulary file is inconsistent: " + e.what());
  }
}

}  // namespace groundslam
