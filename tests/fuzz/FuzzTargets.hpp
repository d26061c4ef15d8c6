#pragma once
// The parsers under fuzzing, one entry point each, shared by the libFuzzer executables (tests/fuzz/fuzz_*.cpp,
// `make fuzz`) and the GoogleTest replay of tests/data/fuzz/ (tests/test_fuzz_regressions.cpp, `make test`).
//
// Each function feeds arbitrary bytes to one parser. A parser may return or throw groundslam::InputError;
// both are swallowed here. Anything else escapes: another exception (libFuzzer reports it as a crash, the
// replay test as a failure), a crash, a hang or a sanitizer report. A vocabulary that parses but then gives
// a word outside [0, wordCount) throws FuzzInvariantError, which escapes too.

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace groundslam::fuzz {

/// A parsed result that breaks a promise of its type (thrown only by the fuzz entry points).
class FuzzInvariantError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

/// HD Ground list: the first byte chooses `with_poses` (odd: a `.txt` list with pose lines), the rest is the text.
void fuzzHdGroundList(const std::uint8_t* data, size_t size);
/// TUM trajectory text.
void fuzzTum(const std::uint8_t* data, size_t size);
/// Configuration YAML applied over the defaults, then the required-key check.
void fuzzConfigYaml(const std::uint8_t* data, size_t size);
/// Vocabulary file. The first byte is a mode: bit 0 clear, the checksum is recomputed (so the structure is
/// what gets fuzzed, not the FNV-1a); bit 1 set, the bytes are also cut or zero-padded to the size the
/// header promises first. On success, descriptors taken from the input go through wordOf and transform.
void fuzzVocabulary(const std::uint8_t* data, size_t size);

/// Map file (map.gsmap); bit 0 of the first byte clear: the checksum is recomputed. On success every
/// feature's position is computed through its keyframe.
void fuzzMap(const std::uint8_t* data, size_t size);

/// The vocabulary bytes fuzzVocabulary parses for an input (mode byte applied and removed).
std::string vocabularyBytesFor(const std::uint8_t* data, size_t size);

struct FuzzTarget {
  const char* name;  ///< also the folder under tests/data/fuzz/ holding its seeds and regression inputs
  void (*run)(const std::uint8_t* data, size_t size);
};

/// Every target, by name: hd_ground_list, tum, config_yaml, vocabulary, map.
const std::vector<FuzzTarget>& fuzzTargets();

}  // namespace groundslam::fuzz
