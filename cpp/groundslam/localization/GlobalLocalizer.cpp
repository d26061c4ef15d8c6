#include "groundslam/localization/GlobalLocalizer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "groundslam/core/Hamming.hpp"
#include "groundslam/core/Matching.hpp"

namespace groundslam {
namespace {

/// A vote cell (x, y, heading) packed into one key; the heading index wraps around.
struct VoteGrid {
  double cell_m, cell_rad;
  int heading_cells;

  VoteGrid(const LocalizationSettings& s)
      : cell_m(s.cell_m), cell_rad(s.cell_deg * M_PI / 180.0), heading_cells(std::max(1, static_cast<int>(std::round(2.0 * M_PI / cell_rad)))) {
    cell_rad = 2.0 * M_PI / heading_cells;
  }
  std::uint64_t key(std::int64_t ix, std::int64_t iy, std::int64_t it) const {
    it = ((it % heading_cells) + heading_cells) % heading_cells;
    return (static_cast<std::uint64_t>(ix + (1 << 20)) & 0x1fffff) << 42 | (static_cast<std::uint64_t>(iy + (1 << 20)) & 0x1fffff) << 21 |
           static_cast<std::uint64_t>(it);
  }
  std::array<std::int64_t, 3> cellOf(const Pose2& T) const {
    return {static_cast<std::int64_t>(std::floor(T.x / cell_m)), static_cast<std::int64_t>(std::floor(T.y / cell_m)),
            static_cast<std::int64_t>(std::floor((T.theta + M_PI) / cell_rad))};
  }
  Pose2 centreOf(const std::array<std::int64_t, 3>& c) const {
    return Pose2((static_cast<double>(c[0]) + 0.5) * cell_m, (static_cast<double>(c[1]) + 0.5) * cell_m,
                 wrapAngle((static_cast<double>(c[2]) + 0.5) * cell_rad - M_PI));
  }
  /// Cells apart in heading, the short way round.
  std::int64_t headingApart(std::int64_t a, std::int64_t b) const {
    const std::int64_t d = std::abs(((a - b) % heading_cells + heading_cells) % heading_cells);
    return std::min<std::int64_t>(d, heading_cells - d);
  }
};

struct Vote {
  std::uint32_t query;
  std::uint32_t feature;
};

struct Cell {
  std::array<std::int64_t, 3> index;
  std::vector<Vote> votes;
};

struct Peak {
  std::array<std::int64_t, 3> index;
  int votes = 0;  ///< in the 3x3x3 neighbourhood
};

/// Every (query feature, map feature) pair sharing a visual word, with close descriptors and octaves,
/// votes for the robot pose the pair implies.
std::unordered_map<std::uint64_t, Cell> castVotes(const FeatureMap& map, const GroundFeatures& query, const VoteGrid& grid,
                                                  const LocalizationSettings& s, const AnchorFilter& usable) {
  std::unordered_map<std::uint64_t, Cell> cells;
  for (size_t q = 0; q < query.size(); ++q) {
    const std::uint8_t* descriptor = query.descriptors.ptr<std::uint8_t>(static_cast<int>(q));
    const auto& postings = map.postings(map.vocabulary().wordOf(descriptor));
    if (postings.size() > static_cast<size_t>(s.max_postings)) continue;
    for (const std::uint32_t index : postings) {
      const MapFeature& f = map.features()[index];
      if (!usable.empty() && !usable[f.anchor]) continue;
      if (std::abs(static_cast<int>(f.octave) - static_cast<int>(query.octaves[q])) > 1) continue;
      if (hammingDistance256(descriptor, f.descriptor.data()) > s.max_hamming) continue;
      // T_map_robot = T_map_feature * T_robot_feature^-1, both features as (position, orientation).
      const double theta = wrapAngle(map.angleOf(f) - query.angles_rad[q]);
      const Eigen::Vector2d t = map.positionOf(f) - Eigen::Rotation2Dd(theta) * query.points[q];
      const auto c = grid.cellOf(Pose2(t.x(), t.y(), theta));
      Cell& cell = cells[grid.key(c[0], c[1], c[2])];
      cell.index = c;
      cell.votes.push_back({static_cast<std::uint32_t>(q), index});
    }
  }
  return cells;
}

template <class F>
void forEachNeighbour(const std::unordered_map<std::uint64_t, Cell>& cells, const VoteGrid& grid,
                      const std::array<std::int64_t, 3>& c, F&& f) {
  for (std::int64_t dx = -1; dx <= 1; ++dx) {
    for (std::int64_t dy = -1; dy <= 1; ++dy) {
      for (std::int64_t dt = -1; dt <= 1; ++dt) {
        const auto it = cells.find(grid.key(c[0] + dx, c[1] + dy, c[2] + dt));
        if (it != cells.end()) f(it->second);
      }
    }
  }
}

/// The strongest neighbourhoods, each at least two cells from a stronger one.
std::vector<Peak> findPeaks(const std::unordered_map<std::uint64_t, Cell>& cells, const VoteGrid& grid, size_t wanted) {
  std::vector<Peak> scored;
  scored.reserve(cells.size());
  for (const auto& [key, cell] : cells) {
    int votes = 0;
    forEachNeighbour(cells, grid, cell.index, [&](const Cell& n) { votes += static_cast<int>(n.votes.size()); });
    scored.push_back({cell.index, votes});
  }
  std::sort(scored.begin(), scored.end(), [](const Peak& a, const Peak& b) {
    return a.votes > b.votes || (a.votes == b.votes && a.index < b.index);
  });
  std::vector<Peak> peaks;
  for (const Peak& p : scored) {
    const bool near_stronger = std::any_of(peaks.begin(), peaks.end(), [&](const Peak& q) {
      return std::abs(p.index[0] - q.index[0]) <= 2 && std::abs(p.index[1] - q.index[1]) <= 2 &&
             grid.headingApart(p.index[2], q.index[2]) <= 2;
    });
    if (near_stronger) continue;
    peaks.push_back(p);
    if (peaks.size() >= wanted) break;
  }
  return peaks;
}

/// Fraction of the query features' extent (the smaller of the two axes) that the inliers span.
double inlierSpread(const std::vector<Eigen::Vector2d>& inlier_points, const GroundFeatures& query) {
  if (inlier_points.empty() || query.size() == 0) return 0.0;
  const auto extent = [](const auto& points, auto get) {
    Eigen::Vector2d lo = get(points.front()), hi = lo;
    for (const auto& p : points) lo = lo.cwiseMin(get(p)), hi = hi.cwiseMax(get(p));
    return Eigen::Vector2d(hi - lo);
  };
  const auto identity = [](const Eigen::Vector2d& p) { return p; };
  const Eigen::Vector2d all = extent(query.points, identity), inliers = extent(inlier_points, identity);
  return std::min(inliers.x() / std::max(all.x(), 1e-9), inliers.y() / std::max(all.y(), 1e-9));
}

/// Every usable map feature near the predicted pose, in map coordinates, for guided re-matching.
GroundFeatures mapFeaturesAround(const FeatureMap& map, const Eigen::Vector2d& where, double radius_m, const AnchorFilter& usable) {
  GroundFeatures around;
  for (const int a : map.anchorsNear(where, radius_m)) {
    if (!usable.empty() && !usable[static_cast<size_t>(a)]) continue;
    for (const std::uint32_t i : map.featuresOf(a)) {
      const MapFeature& f = map.features()[i];
      around.points.push_back(map.positionOf(f));
      around.descriptors.push_back(cv::Mat(1, 32, CV_8U, const_cast<std::uint8_t*>(f.descriptor.data())));
    }
  }
  return around;
}

struct Verified {
  RigidEstimate fit;
  std::vector<Eigen::Vector2d> inlier_query_points;
  int strong_inliers = 0;  ///< inliers whose descriptors are within settings.strong_hamming bits
};

/// Robust fit of the pairs that voted for a peak, refined by guided re-matching in the predicted footprint.
std::optional<Verified> verifyPeak(const FeatureMap& map, const GroundFeatures& query, const Peak& peak,
                                   const std::unordered_map<std::uint64_t, Cell>& cells, const VoteGrid& grid,
                                   const LocalizationSettings& s, FitSettings fitting, const AnchorFilter& usable) {
  std::vector<Eigen::Vector2d> target, source;
  forEachNeighbour(cells, grid, peak.index, [&](const Cell& c) {
    for (const Vote& v : c.votes) {
      target.push_back(map.positionOf(map.features()[v.feature]));
      source.push_back(query.points[v.query]);
    }
  });
  fitting.min_inliers = std::min(fitting.min_inliers, s.min_votes);
  const TransformPrior around_peak{grid.centreOf(peak.index), 2.0 * grid.cell_m, 2.0 * grid.cell_rad};
  const RigidEstimate coarse = fitRigidTransform(target, source, fitting, around_peak);
  if (!coarse.ok()) return std::nullopt;
  const GroundFeatures nearby = mapFeaturesAround(map, coarse.T_target_source.translation(), s.footprint_radius_m, usable);
  const std::vector<Match> matches = matchNearby(query, nearby, coarse.T_target_source, s.match_radius_m, s.ratio);
  target.clear();
  source.clear();
  for (const Match& m : matches) {
    target.push_back(nearby.points[static_cast<size_t>(m.train)]);
    source.push_back(query.points[static_cast<size_t>(m.query)]);
  }
  const TransformPrior around_coarse{coarse.T_target_source, s.match_radius_m, 2.0 * M_PI / 180.0};
  Verified verified{fitRigidTransform(target, source, fitting, around_coarse), {}, 0};
  for (size_t i = 0; i < target.size(); ++i) {
    if ((verified.fit.T_target_source * source[i] - target[i]).norm() <= fitting.ransac_inlier_m) {
      verified.inlier_query_points.push_back(source[i]);
      verified.strong_inliers += matches[i].distance <= s.strong_hamming ? 1 : 0;
    }
  }
  return verified;
}

/// The most votes another peak may have, as a share of the winner's. A floor shows that it repeats when a rival pose
/// verifies with min_inliers inliers: there every repetition collects votes, and those not verified are judged by
/// them. Elsewhere a weak winner's dozen votes are matched by chance peaks, which its verified inliers outweigh.
double voteRatioFor(int rival_inliers, const LocalizationSettings& s) {
  return rival_inliers >= s.min_inliers ? s.max_vote_ratio : std::max(s.max_vote_ratio, s.unrepeated_max_vote_ratio);
}

}  // namespace

const char* localizationStatusName(LocalizationStatus status) {
  switch (status) {
    case LocalizationStatus::localized: return "localized";
    case LocalizationStatus::too_few_votes: return "too_few_votes";
    case LocalizationStatus::ambiguous: return "ambiguous";
    case LocalizationStatus::too_few_inliers: return "too_few_inliers";
    case LocalizationStatus::covariance: return "covariance";
    case LocalizationStatus::clustered: return "clustered";
  }
  return "unknown";
}

bool onTheEarlierPose(const Pose2& T_a_b, const LocalizationSettings& settings) {
  return T_a_b.translation().norm() < settings.min_anchor_offset_m && std::abs(T_a_b.theta) < settings.min_anchor_offset_rad;
}

Localization localizeGlobally(const FeatureMap& map, const GroundFeatures& query, const LocalizationSettings& s,
                              const FitSettings& fitting, const AnchorFilter& usable) {
  Localization result;
  if (!query.hasOrientations() || map.features().empty()) return result;
  const VoteGrid grid(s);
  const auto cells = castVotes(map, query, grid, s, usable);
  const std::vector<Peak> peaks = findPeaks(cells, grid, static_cast<size_t>(s.max_peaks) + 1);
  if (peaks.empty() || peaks.front().votes < s.min_votes) return result;
  // Verify the strongest peaks; the one whose pose the most map features confirm wins. On a repetitive floor
  // another repetition is confirmed almost as well: the winner must clearly beat every rival pose.
  result.status = LocalizationStatus::too_few_inliers;
  std::vector<std::pair<Verified, size_t>> verified;  // with the peak's index
  for (size_t p = 0; p < peaks.size() && p < static_cast<size_t>(s.max_peaks); ++p) {
    if (peaks[p].votes < s.min_votes) break;
    auto v = verifyPeak(map, query, peaks[p], cells, grid, s, fitting, usable);
    if (v && v->fit.ok()) verified.emplace_back(std::move(*v), p);
  }
  if (verified.empty()) return result;
  std::sort(verified.begin(), verified.end(), [](const auto& a, const auto& b) { return a.first.fit.inliers > b.first.fit.inliers; });
  const Verified& best = verified.front().first;
  int rival = 0;
  for (size_t i = 1; i < verified.size(); ++i) {
    const Pose2 difference = best.fit.T_target_source.inverse() * verified[i].first.fit.T_target_source;
    if (difference.translation().norm() > 2.0 * s.match_radius_m || std::abs(difference.theta) > 2.0 * M_PI / 180.0) {
      rival = std::max(rival, verified[i].first.fit.inliers);
    }
  }
  result.T_map_robot = best.fit.T_target_source;
  result.covariance = best.fit.covariance;
  const size_t winner = verified.front().second;
  result.votes = peaks[winner].votes;
  result.inliers = best.fit.inliers;
  result.runner_up_inliers = rival;
  // Votes too: on a repetitive floor many peaks, one per repetition, collect about as many votes.
  int rival_votes = 0;
  for (size_t p = 0; p < peaks.size(); ++p) {
    if (p != winner) rival_votes = std::max(rival_votes, peaks[p].votes);
  }
  result.runner_up_votes = rival_votes;
  result.strong_inliers = best.strong_inliers;
  if (result.inliers < s.min_inliers || best.strong_inliers < s.min_strong_inliers) {
    result.status = LocalizationStatus::too_few_inliers;
  } else if (static_cast<double>(rival) > s.max_rival_ratio * static_cast<double>(result.inliers) ||
             static_cast<double>(rival_votes) > voteRatioFor(rival, s) * static_cast<double>(result.votes)) {
    result.status = LocalizationStatus::ambiguous;
  } else if (best.fit.covarianceScore() > s.max_covariance_score) {
    result.status = LocalizationStatus::covariance;
  } else if (inlierSpread(best.inlier_query_points, query) < s.min_spread) {
    result.status = LocalizationStatus::clustered;
  } else {
    result.status = LocalizationStatus::localized;
  }
  if (!result.ok()) return result;
  // The nearest anchor, and the pose and covariance relative to it (a graph edge from that keyframe).
  double nearest = std::numeric_limits<double>::infinity();
  for (size_t a = 0; a < map.anchors().size(); ++a) {
    if (!usable.empty() && !usable[a]) continue;
    const double d = (map.anchors()[a].T_map_anchor.translation() - result.T_map_robot.translation()).norm();
    if (d < nearest) nearest = d, result.anchor = static_cast<int>(a);
  }
  const Pose2& T_map_anchor = map.anchors()[static_cast<size_t>(result.anchor)].T_map_anchor;
  result.T_anchor_robot = T_map_anchor.inverse() * result.T_map_robot;
  Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
  J.topLeftCorner<2, 2>() = T_map_anchor.rotation().transpose();
  result.anchor_covariance = J * result.covariance * J.transpose();
  return result;
}

}  // namespace groundslam
