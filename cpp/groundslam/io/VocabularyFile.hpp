#pragma once
// The vocabulary's binary file: magic "GSLMVOC", format version, tree shape, nodes, IDF weights and an
// FNV-1a checksum of everything before it. Little-endian.

#include <string>

#include "groundslam/bow/Vocabulary.hpp"

namespace groundslam {

constexpr unsigned kVocabularyFormatVersion = 1;

void writeVocabulary(const std::string& path, const Vocabulary& vocabulary);
/// Throws InputError naming the file when it is missing, truncated, corrupt or of another version.
Vocabulary readVocabulary(const std::string& path);
/// Parses a vocabulary file's bytes; `source` names it in errors. Validates the structure, not only the
/// checksum. Throws InputError.
Vocabulary parseVocabulary(const std::string& bytes, const std::string& source);

}  // namespace groundslam
