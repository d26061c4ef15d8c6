#include "groundslam/io/VocabularyFile.hpp"

#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "groundslam/io/BinaryFormat.hpp"
#include "groundslam/io/Files.hpp"
#include "groundslam/io/InputError.hpp"

namespace groundslam {
namespace {

constexpr char kMagic[8] = {'G', 'S', 'L', 'M', 'V', 'O', 'C', '\0'};

}  // namespace

void writeVocabulary(const std::string& path, const Vocabulary& vocabulary) {
  std::string out(kMagic, sizeof(kMagic));
  putValue(out, std::uint32_t{kVocabularyFormatVersion});
  putValue(out, static_cast<std::uint32_t>(vocabulary.branching()));
  putValue(out, static_cast<std::uint32_t>(vocabulary.depth()));
  putValue(out, static_cast<std::uint32_t>(vocabulary.nodes().size()));
  putValue(out, static_cast<std::uint32_t>(vocabulary.idf().size()));
  for (const auto& node : vocabulary.nodes()) {
    out.append(reinterpret_cast<const char*>(node.centre.data()), node.centre.size());
    putValue(out, std::int32_t{node.first_child});
    putValue(out, std::int32_t{node.child_count});
    putValue(out, std::int32_t{node.word});
  }
  for (double w : vocabulary.idf()) putValue(out, w);
  putChecksum(out);
  writeFileAtomically(path, out);
}

Vocabulary readVocabulary(const std::string& path) { return parseVocabulary(readTextFile(path), path); }

Vocabulary parseVocabulary(const std::string& bytes, const std::string& path) {
  if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    throw InputError(path + ": not a groundslam vocabulary file (bad magic)");
  }
  BinaryReader in(bytes, path, "vocabulary");
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
  if (!checksumMatches(bytes)) throw InputError(path + ": vocabulary file is corrupt (checksum)");
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
