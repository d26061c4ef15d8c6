// PipelinedSlam: images pushed one by one, prepared on another thread, give exactly Slam::process's results.
#include <gtest/gtest.h>

#include "groundslam/io/VocabularyFile.hpp"
#include "groundslam/pipeline/PipelinedSlam.hpp"
#include "groundslam/sim/Simulator.hpp"

using namespace groundslam;

TEST(PipelinedSlam, GivesSlamsResultsOneFrameLate) {
  sim::SimulationSettings settings;
  settings.path.kind = sim::PathKind::loop;
  settings.path.frames = 140;  // more than a lap: loop closures happen
  settings.photometry.noise_sigma = 2.0;
  const sim::SequenceSimulator simulator(settings);
  Config config;
  config.camera = cameraConfigOf(settings.camera, settings.mounting_height_m);
  const auto vocabulary =
      std::make_shared<const Vocabulary>(readVocabulary(std::string(GROUNDSLAM_SOURCE_DIR) + "/config/vocabulary/ground.gslmvoc"));

  Slam direct(config, vocabulary);
  std::vector<FrameResult> expected;
  for (int i = 0; i < simulator.frameCount(); ++i) expected.push_back(direct.process(simulator.renderFrame(i), 0.1 * i));
  direct.finish();

  Slam slam(config, vocabulary);
  PipelinedSlam pipelined(slam);
  std::vector<FrameResult> results;
  cv::Mat buffer;  // one buffer reused for every image, as a camera driver does
  for (int i = 0; i < simulator.frameCount(); ++i) {
    simulator.renderFrame(i).copyTo(buffer);
    const std::optional<FrameResult> r = pipelined.push(buffer, 0.1 * i);
    EXPECT_EQ(r.has_value(), i > 0) << i;
    if (r) results.push_back(*r);
  }
  const std::optional<FrameResult> last = pipelined.finish();
  ASSERT_TRUE(last.has_value());
  results.push_back(*last);

  ASSERT_EQ(results.size(), expected.size());
  int loop_closures = 0;
  for (size_t i = 0; i < results.size(); ++i) {
    EXPECT_EQ(results[i].index, expected[i].index);
    EXPECT_EQ(results[i].statusName(), expected[i].statusName()) << i;
    EXPECT_EQ(results[i].inliers, expected[i].inliers) << i;
    EXPECT_EQ(results[i].loop_closures, expected[i].loop_closures) << i;
    loop_closures += results[i].loop_closures;
  }
  EXPECT_GT(loop_closures, 0);
  const Trajectory a = direct.trajectory(), b = slam.trajectory();
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].timestamp, b[i].timestamp);
    EXPECT_EQ(a[i].T_world_robot.x, b[i].T_world_robot.x) << i;
    EXPECT_EQ(a[i].T_world_robot.y, b[i].T_world_robot.y) << i;
    EXPECT_EQ(a[i].T_world_robot.theta, b[i].T_world_robot.theta) << i;
  }
  EXPECT_FALSE(pipelined.finish().has_value());  // nothing pushed since
}

TEST(PipelinedSlam, RefusesAnImageOfAnotherSize) {
  sim::SimulationSettings settings;
  Config config;
  config.camera = cameraConfigOf(settings.camera, settings.mounting_height_m);
  Slam slam(config, nullptr);
  PipelinedSlam pipelined(slam);
  try {
    pipelined.push(cv::Mat(10, 20, CV_8U, cv::Scalar(0)), 0.0);
    FAIL() << "accepted a 20x10 image";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "image is 20x10, the camera configuration says 320x240 8-bit grey");
  }
}
