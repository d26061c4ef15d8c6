#include "groundslam/io/MapFile.hpp"

#include <cmath>
#include <cstring>

#include "groundslam/io/BinaryFormat.hpp"
#include "groundslam/io/Files.hpp"
#include "groundslam/io/InputError.hpp"

namespace groundslam {
namespace {

constexpr char kMagic[8] = {'G', 'S', 'L', 'M', 'M', 'A', 'P', '\0'};
constexpr size_t kHeaderBytes = 8 + 4 + 4 + 4;
constexpr size_t kAnchorBytes = 4 + 3 * 8 + 4;
constexpr size_t kFeatureBytes = 32 + 3 * 4 + 4 + 1;
constexpr double kMaxCoordinateM = 1e6;  // a map beyond a thousand kilometres is not a floor

bool plausible(double value, double limit) { return std::isfinite(value) && std::abs(value) <= limit; }

}  // namespace

std::string formatMap(const FeatureMap& map, int segment) {
  std::vector<int> new_index(map.anchors().size(), -1);
  std::vector<const MapAnchor*> anchors;
  for (size_t a = 0; a < map.anchors().size(); ++a) {
    if (map.anchors()[a].segment != segment) continue;
    new_index[a] = static_cast<int>(anchors.size());
    anchors.push_back(&map.anchors()[a]);
  }
  std::vector<const MapFeature*> features;
  for (const MapFeature& f : map.features()) {
    if (new_index[f.anchor] >= 0) features.push_back(&f);
  }
  std::string out(kMagic, sizeof(kMagic));
  putValue(out, std::uint32_t{kMapFormatVersion});
  putValue(out, static_cast<std::uint32_t>(anchors.size()));
  putValue(out, static_cast<std::uint32_t>(features.size()));
  for (const MapAnchor* a : anchors) {
    putValue(out, std::int32_t{a->frame});
    putValue(out, a->T_map_anchor.x);
    putValue(out, a->T_map_anchor.y);
    putValue(out, a->T_map_anchor.theta);
    putValue(out, std::int32_t{0});  // one segment: the map frame
  }
  for (const MapFeature* f : features) {
    out.append(reinterpret_cast<const char*>(f->descriptor.data()), f->descriptor.size());
    putValue(out, f->point.x());
    putValue(out, f->point.y());
    putValue(out, f->angle_rad);
    putValue(out, static_cast<std::uint32_t>(new_index[f->anchor]));
    putValue(out, f->octave);
  }
  putChecksum(out);
  return out;
}

void writeMap(const std::string& path, const FeatureMap& map, int segment) { writeFileAtomically(path, formatMap(map, segment)); }

FeatureMap readMap(const std::string& path, std::shared_ptr<const Vocabulary> vocabulary) {
  return parseMap(readTextFile(path), path, std::move(vocabulary));
}

FeatureMap parseMap(const std::string& bytes, const std::string& path, std::shared_ptr<const Vocabulary> vocabulary) {
  if (!vocabulary) throw InputError(path + ": reading a map needs the vocabulary it was built with (loop closure is off)");
  if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    throw InputError(path + ": not a groundslam map file (bad magic)");
  }
  BinaryReader in(bytes, path, "map");
  in.skip(sizeof(kMagic));
  const auto version = in.get<std::uint32_t>();
  if (version != kMapFormatVersion) {
    throw InputError(path + ": map format version " + std::to_string(version) + ", this groundslam reads version " +
                     std::to_string(kMapFormatVersion));
  }
  const auto anchor_count = in.get<std::uint32_t>(), feature_count = in.get<std::uint32_t>();
  const size_t expected = kHeaderBytes + size_t{anchor_count} * kAnchorBytes + size_t{feature_count} * kFeatureBytes + 8;
  if (bytes.size() != expected) {
    throw InputError(path + ": map file is " + std::to_string(bytes.size()) + " bytes, its header promises " +
                     std::to_string(expected) + " (truncated or corrupt)");
  }
  if (!checksumMatches(bytes)) throw InputError(path + ": map file is corrupt (checksum)");
  const auto broken = [&](const std::string& what) { throw InputError(path + ": map file is inconsistent: " + what); };
  if (anchor_count == 0 || feature_count == 0) broken("it holds no keyframes or no features");
  FeatureMap map(std::move(vocabulary));
  for (std::uint32_t a = 0; a < anchor_count; ++a) {
    MapAnchor anchor;
    anchor.frame = in.get<std::int32_t>();
    const double x = in.get<double>(), y = in.get<double>(), theta = in.get<double>();
    anchor.segment = in.get<std::int32_t>();
    if (!plausible(x, kMaxCoordinateM) || !plausible(y, kMaxCoordinateM) || !plausible(theta, 4.0) || anchor.segment != 0) {
      broken("keyframe " + std::to_string(a) + " has a pose that is not finite, not plausible or not in the map frame");
    }
    anchor.T_map_anchor = Pose2(x, y, theta);
    map.addStoredAnchor(anchor);
  }
  for (std::uint32_t i = 0; i < feature_count; ++i) {
    MapFeature f;
    for (auto& byte : f.descriptor) byte = in.get<std::uint8_t>();
    const float x = in.get<float>(), y = in.get<float>(), angle = in.get<float>();
    f.anchor = in.get<std::uint32_t>();
    f.octave = in.get<std::uint8_t>();
    if (f.anchor >= anchor_count) broken("feature " + std::to_string(i) + " names keyframe " + std::to_string(f.anchor) + " of " + std::to_string(anchor_count));
    if (!plausible(x, 10.0) || !plausible(y, 10.0) || !plausible(angle, 4.0) || f.octave > 31) {
      broken("feature " + std::to_string(i) + " has a position, orientation or octave that is not plausible");
    }
    f.point = Eigen::Vector2f(x, y);
    f.angle_rad = angle;
    map.addStoredFeature(f);
  }
  return map;
}

}  // namespace groundslam
