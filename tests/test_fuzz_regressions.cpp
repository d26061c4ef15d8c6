// Replays the fuzzers' seed corpus and every saved crash input (tests/data/fuzz/<target>/) through the same
// entry points as the libFuzzer executables (tests/fuzz/FuzzTargets.cpp): each input must parse or throw
// InputError; any other exception fails here, a crash or sanitizer report fails the test process.
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <ostream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "FuzzTargets.hpp"
#include "groundslam/io/VocabularyFile.hpp"

namespace groundslam::fuzz {
// Names the target in test output instead of its bytes.
void PrintTo(const FuzzTarget& target, std::ostream* os) { *os << target.name; }
}  // namespace groundslam::fuzz

namespace fs = std::filesystem;
using groundslam::fuzz::FuzzTarget;

namespace {

std::vector<fs::path> inputsOf(const std::string& target) {
  std::vector<fs::path> files;
  const fs::path dir = fs::path(GROUNDSLAM_SOURCE_DIR) / "tests" / "data" / "fuzz" / target;
  if (!fs::is_directory(dir)) return files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string bytesOf(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

class FuzzRegressions : public ::testing::TestWithParam<FuzzTarget> {};

TEST_P(FuzzRegressions, EveryInputParsesOrThrowsInputError) {
  const FuzzTarget target = GetParam();
  const auto files = inputsOf(target.name);
  ASSERT_FALSE(files.empty()) << "no inputs under tests/data/fuzz/" << target.name;
  for (const auto& file : files) {
    SCOPED_TRACE(file.string());
    const std::string bytes = bytesOf(file);
    EXPECT_NO_THROW(target.run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
  }
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzRegressions, ::testing::ValuesIn(groundslam::fuzz::fuzzTargets()),
                         [](const ::testing::TestParamInfo<FuzzTarget>& info) { return std::string(info.param.name); });

}  // namespace

// The seed corpus must reach the parsers' success paths, not only their first error: the valid seeds parse.
TEST(FuzzSeeds, ValidVocabularySeedParses) {
  const std::string bytes = bytesOf(fs::path(GROUNDSLAM_SOURCE_DIR) / "tests/data/fuzz/vocabulary/valid_tiny.gslmvoc");
  ASSERT_FALSE(bytes.empty());
  ASSERT_EQ(static_cast<unsigned char>(bytes[0]), 1u) << "mode byte 1: the stored checksum is kept";
  EXPECT_NO_THROW(groundslam::parseVocabulary(groundslam::fuzz::vocabularyBytesFor(
                                                  reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()),
                                              "valid_tiny.gslmvoc"));
}
