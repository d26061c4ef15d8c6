// Global localization with no pose prior: a map built from one simulated session, queried by another
// session (other path, other noise) over the same ground.
#include <chrono>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "groundslam/io/VocabularyFile.hpp"
#include "groundslam/localization/GlobalLocalizer.hpp"
#include "groundslam/pipeline/FramePreparer.hpp"
#include "groundslam/sim/Simulator.hpp"

using namespace groundslam;

namespace {

std::shared_ptr<const Vocabulary> shippedVocabulary() {
  static const auto vocabulary =
      std::make_shared<const Vocabulary>(readVocabulary(std::string(GROUNDSLAM_SOURCE_DIR) + "/config/vocabulary/ground.gslmvoc"));
  return vocabulary;
}

sim::SimulationSettings session(const std::string& texture, sim::PathKind path, int frames, std::uint64_t seed) {
  sim::SimulationSettings s;
  s.texture_kind = texture;
  s.path.kind = path;
  s.path.frames = frames;
  s.path.seed = seed;
  s.seed = seed;
  s.ground_seed = 11;
  s.ground_size_m = 1.6;
  s.photometry.noise_sigma = 2.0;
  return s;
}

Config configFor(const sim::SimulationSettings& s) {
  Config c;
  c.camera = cameraConfigOf(s.camera, s.mounting_height_m);
  return c;
}

/// A map from a session's frames at their true poses, one keyframe every `spacing` frames.
FeatureMap mapOf(const sim::SequenceSimulator& simulator, const FramePreparer& preparer, int spacing) {
  FeatureMap map(shippedVocabulary());
  for (int i = 0; i < simulator.frameCount(); i += spacing) {
    map.addAnchor(i, simulator.groundTruth()[static_cast<size_t>(i)], 0, preparer.prepare(simulator.renderFrame(i), i).features);
  }
  return map;
}

struct Score {
  int on_map = 0;      ///< query frames within 5 cm of a map keyframe
  int localized = 0;   ///< of those, localized within 1 cm and 1 degree
  int wrong = 0;       ///< localized anywhere more than 5 cm or 2 degrees off
  double total_ms = 0.0;
  int tried = 0;
};

Score localizeSession(const FeatureMap& map, const sim::SequenceSimulator& queries, const FramePreparer& preparer, int step,
                      const Config& config) {
  Score score;
  const LocalizationSettings settings;
  for (int i = 0; i < queries.frameCount(); i += step) {
    const GroundFeatures features = preparer.prepare(queries.renderFrame(i), i).features;
    const auto start = std::chrono::steady_clock::now();
    const Localization l = localizeGlobally(map, features, settings, config.odometry);
    score.total_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    ++score.tried;
    const Pose2 truth = queries.groundTruth()[static_cast<size_t>(i)];
    double nearest = 1e9;
    for (const auto& a : map.anchors()) nearest = std::min(nearest, (a.T_map_anchor.translation() - truth.translation()).norm());
    const double e_t = (l.T_map_robot.translation() - truth.translation()).norm();
    const double e_r = std::abs(wrapAngle(l.T_map_robot.theta - truth.theta)) * 180.0 / M_PI;
    if (nearest < 0.05) ++score.on_map;
    if (l.ok() && e_t < 0.01 && e_r < 1.0 && nearest < 0.05) ++score.localized;
    if (l.ok() && (e_t > 0.05 || e_r > 2.0)) ++score.wrong;
  }
  return score;
}

Score secondSession(const std::string& texture) {
  auto mapping = session(texture, sim::PathKind::lawnmower, 500, 1);
  mapping.path.lane_length_m = 0.5;
  const sim::SequenceSimulator first(mapping);
  const FramePreparer preparer(configFor(mapping));
  const FeatureMap map = mapOf(first, preparer, 3);
  auto second_settings = session(texture, sim::PathKind::random_walk, 200, 2);
  second_settings.path.area_m = 0.4;
  const sim::SequenceSimulator second(second_settings);
  const Score s = localizeSession(map, second, preparer, 5, configFor(mapping));
  std::printf("%s: map of %zu features (%.1f B each); %d of %d query frames on mapped ground, %d localized there, %d wrong; "
              "%.1f ms per localization\n", texture.c_str(), map.features().size(), double(map.bytes()) / double(map.features().size()),
              s.on_map, s.tried, s.localized, s.wrong, s.total_ms / s.tried);
  return s;
}

}  // namespace

TEST(GlobalLocalization, ASecondSessionLocalizesOnTheFirstSessionsMap) {
  const Score s = secondSession("asphalt");
  ASSERT_GE(s.on_map, 15);
  EXPECT_GE(s.localized, 0.95 * s.on_map);
  EXPECT_EQ(s.wrong, 0);
}

TEST(GlobalLocalization, TilesAreRefusedRatherThanLocalizedOneTileOff) {
  // Every tile carries the same pattern: the pose one tile over is confirmed as well as the true one, so
  // with no prior the localizer must refuse, never pick a repetition.
  const Score s = secondSession("tiles");
  EXPECT_EQ(s.wrong, 0);
}
