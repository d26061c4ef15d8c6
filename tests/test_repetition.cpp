// Whether the ground repeats, from one image (core/Repetition.hpp): the simulator's tiles, seen under the outdoor
// look, repeat; its asphalt, concrete and carpet never do, whatever the frame.
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "groundslam/core/Repetition.hpp"
#include "groundslam/sim/Simulator.hpp"
#include "OutdoorLook.hpp"

using namespace groundslam;

namespace {

/// The repetition strength of frames 0, 50, ..., 350 of a 400-frame random walk over `texture` under the outdoor look.
std::vector<double> strengthsAlongAWalk(const std::string& texture, std::uint64_t seed) {
  sim::SimulationSettings s;
  s.texture_kind = texture;
  s.path.kind = sim::PathKind::random_walk;
  s.path.frames = 400;
  s.path.seed = s.seed = seed;
  groundslam::testing::putUnderTheOutdoorLook(s);
  const sim::SequenceSimulator simulator(s);
  std::vector<double> strengths;
  for (int frame = 0; frame < 400; frame += 50) strengths.push_back(repetitionStrength(simulator.renderFrame(frame)));
  return strengths;
}

}  // namespace

TEST(Repetition, TilesRepeatUnderTheOutdoorLook) {
  // Every tile carries one speckle pattern: the autocorrelation rises again one tile (4 cm) over. Above 0.25 on every
  // frame, clear of the default odometry.floor_repeat_min_strength (0.22); measured 0.27-0.29 on the weakest two.
  for (const double strength : strengthsAlongAWalk("tiles", 5)) EXPECT_GT(strength, 0.25);
}

TEST(Repetition, GrainyFloorsDoNotRepeat) {
  // Their autocorrelation only decays (carpet's drawn-out grain keeps correlating along it, ever less).
  for (const char* texture : {"asphalt", "concrete", "carpet"}) {
    for (const double strength : strengthsAlongAWalk(texture, 5)) EXPECT_LT(strength, 0.2) << texture;
  }
}

TEST(Repetition, UnusableImagesGiveNone) {
  EXPECT_EQ(repetitionStrength(cv::Mat()), 0.0);
  EXPECT_EQ(repetitionStrength(cv::Mat::zeros(240, 320, CV_8U)), 0.0);  // blank
  EXPECT_EQ(repetitionStrength(cv::Mat::zeros(8, 8, CV_32F)), 0.0);     // too small
  EXPECT_EQ(repetitionStrength(cv::Mat::zeros(240, 320, CV_8UC3)), 0.0);  // not one channel
}
