#include "FuzzTargets.hpp"

#include <algorithm>
#include <cstring>
#include <memory>

#include <opencv2/core.hpp>

#include "groundslam/bow/Vocabulary.hpp"
#include "groundslam/io/BinaryFormat.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/Dataset.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/Tum.hpp"
#include "groundslam/io/MapFile.hpp"
#include "groundslam/io/VocabularyFile.hpp"

namespace groundslam::fuzz {
namespace {

std::string text(const std::uint8_t* data, size_t size) {
  return size == 0 ? std::string() : std::string(reinterpret_cast<const char*>(data), size);
}

constexpr size_t kHeaderBytes = 8 + 5 * 4;  // magic, version, branching, depth, node count, word count
constexpr size_t kNodeBytes = 32 + 3 * 4;   // centre, first_child, child_count, word
constexpr size_t kMaxPaddedBytes = size_t{1} << 20;

std::uint32_t u32At(const std::string& bytes, size_t offset) {
  std::uint32_t value;
  std::memcpy(&value, bytes.data() + offset, sizeof(value));
  return value;
}

}  // namespace

void fuzzHdGroundList(const std::uint8_t* data, size_t size) {
  const bool with_poses = size > 0 && (data[0] & 1) != 0;
  const std::string list = size > 0 ? text(data + 1, size - 1) : std::string();
  try {
    parseHdGroundList(list, with_poses ? "fuzz.txt" : "fuzz.test", with_poses);
  } catch (const InputError&) {
  }
}

void fuzzTum(const std::uint8_t* data, size_t size) {
  try {
    parseTum(text(data, size), "fuzz.tum");
  } catch (const InputError&) {
  }
}

void fuzzConfigYaml(const std::uint8_t* data, size_t size) {
  try {
    ConfigLoader loader;
    loader.applyText(text(data, size), "fuzz.yaml");
    loader.finish();
  } catch (const InputError&) {
  }
}

std::string vocabularyBytesFor(const std::uint8_t* data, size_t size) {
  if (size == 0) return {};
  const std::uint8_t mode = data[0];
  std::string bytes = text(data + 1, size - 1);
  if ((mode & 2) != 0 && bytes.size() >= kHeaderBytes) {
    const size_t node_count = u32At(bytes, 20), word_count = u32At(bytes, 24);
    const size_t promised = kHeaderBytes + node_count * kNodeBytes + word_count * 8 + 8;
    if (promised <= kMaxPaddedBytes) bytes.resize(promised, '\0');
  }
  if ((mode & 1) == 0) {
    if (bytes.size() < 8) bytes.append(8 - bytes.size(), '\0');
    const std::uint64_t checksum = fnv1a(bytes, bytes.size() - 8);
    std::memcpy(bytes.data() + bytes.size() - 8, &checksum, sizeof(checksum));
  }
  return bytes;
}

void fuzzVocabulary(const std::uint8_t* data, size_t size) {
  const std::string bytes = vocabularyBytesFor(data, size);
  Vocabulary vocabulary;
  try {
    vocabulary = parseVocabulary(bytes, "fuzz.gslmvoc");
  } catch (const InputError&) {
    return;
  }
  // Descriptors from the input itself (cyclically, so that short inputs still give some): a tree that
  // passed validation but is broken shows here as a crash, a hang or a word out of range.
  cv::Mat descriptors(4, 32, CV_8U, cv::Scalar(0));
  for (int r = 0; r < descriptors.rows; ++r) {
    for (int c = 0; c < 32; ++c) {
      const size_t i = static_cast<size_t>(r * 32 + c) * 7 + 3;
      descriptors.at<std::uint8_t>(r, c) = bytes.empty() ? std::uint8_t{0} : static_cast<std::uint8_t>(bytes[i % bytes.size()]);
    }
  }
  const int words = vocabulary.wordCount();
  for (int r = 0; r < descriptors.rows; ++r) {
    const int word = vocabulary.wordOf(descriptors.ptr<std::uint8_t>(r));
    if (word < 0 ? !vocabulary.empty() : word >= words) {
      throw FuzzInvariantError("wordOf gave word " + std::to_string(word) + " of a vocabulary with " +
                               std::to_string(words) + " words");
    }
  }
  for (const auto& [word, weight] : vocabulary.transform(descriptors)) {
    if (word < 0 || word >= words) {
      throw FuzzInvariantError("transform gave word " + std::to_string(word) + " of a vocabulary with " +
                               std::to_string(words) + " words");
    }
    static_cast<void>(weight);
  }
}

void fuzzMap(const std::uint8_t* data, size_t size) {
  // The checksum is recomputed unless bit 0 of the mode byte is set, as for vocabularies.
  std::string bytes = size == 0 ? std::string() : text(data + 1, size - 1);
  if (size > 0 && (data[0] & 1) == 0) {
    if (bytes.size() < 8) bytes.append(8 - bytes.size(), '\0');
    const std::uint64_t checksum = fnv1a(bytes, bytes.size() - 8);
    std::memcpy(bytes.data() + bytes.size() - 8, &checksum, sizeof(checksum));
  }
  // A two-word vocabulary: enough to index the features.
  static const auto vocabulary = std::make_shared<const Vocabulary>(
      2, 1, std::vector<Vocabulary::Node>{{Descriptor{}, 1, 2, -1}, {Descriptor{}, -1, 0, 0}, {Descriptor{}, -1, 0, 1}},
      std::vector<double>{0.5, 0.5});
  try {
    const FeatureMap map = parseMap(bytes, "fuzz.gsmap", vocabulary);
    // Every feature's keyframe must exist and every position be finite.
    for (const MapFeature& f : map.features()) {
      if (!map.positionOf(f).allFinite()) throw FuzzInvariantError("a map feature has a position that is not finite");
    }
  } catch (const InputError&) {
  }
}

const std::vector<FuzzTarget>& fuzzTargets() {
  static const std::vector<FuzzTarget> targets = {
      {"hd_ground_list", fuzzHdGroundList},
      {"tum", fuzzTum},
      {"config_yaml", fuzzConfigYaml},
      {"vocabulary", fuzzVocabulary},
      {"map", fuzzMap},
  };
  return targets;
}

}  // namespace groundslam::fuzz
