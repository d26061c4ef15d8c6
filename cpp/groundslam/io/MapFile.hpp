#pragma once
// The map file (`map.gsmap`) that global localization reuses: magic "GSLMMAP", format version, the
// keyframes (frame index, pose x y theta in the map frame, segment) and the map features (ORB descriptor,
// position and orientation in their keyframe's frame, keyframe index, octave; 49 bytes each), then an
// FNV-1a checksum of everything before it. Little-endian. The map frame is the frame of the first pose of
// the run that built the map. The visual-word index is rebuilt on reading, with the vocabulary given.

#include <memory>
#include <string>

#include "groundslam/bow/Vocabulary.hpp"
#include "groundslam/localization/FeatureMap.hpp"

namespace groundslam {

constexpr unsigned kMapFormatVersion = 1;

/// The bytes of a map file holding the anchors of `segment` (those tied to the map frame) and their features.
std::string formatMap(const FeatureMap& map, int segment);
void writeMap(const std::string& path, const FeatureMap& map, int segment);
/// Throws InputError naming the file when it is missing, truncated, corrupt, of another version, or its
/// structure is broken (an index out of range, a value that is not finite or not plausible).
FeatureMap readMap(const std::string& path, std::shared_ptr<const Vocabulary> vocabulary);
FeatureMap parseMap(const std::string& bytes, const std::string& source, std::shared_ptr<const Vocabulary> vocabulary);

}  // namespace groundslam
