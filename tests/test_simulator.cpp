#include <cmath>
#include <cstdlib>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "TestFiles.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/Dataset.hpp"
#include "groundslam/io/Tum.hpp"
#include "groundslam/sim/Simulator.hpp"

using namespace groundslam;
using groundslam::testing::scratchDir;

namespace {

int runCli(const std::string& args) { return std::system((std::string(GROUNDSLAM_BINARY) + " " + args + " > /dev/null 2>&1").c_str()); }

sim::SimulationSettings smallSettings(sim::PathKind kind, int frames) {
  sim::SimulationSettings s;
  s.camera = sim::scaledHdGroundIntrinsics(160, 120);
  s.path.kind = kind;
  s.path.frames = frames;
  return s;
}

}  // namespace

TEST(Simulator, SequenceReadsBackThroughTheHdGroundReaderExactly) {
  const auto dir = scratchDir();
  ASSERT_EQ(runCli("simulate " + dir.string() + " --frames 12 --resolution 160x120 --path random_walk --jitter-deg 1"
                   " --motion-blur 0.5 --exposure-variation 0.2 --vignetting 0.3 --defocus-px 0.7 --wet-after 0.5"),
            0);
  const Dataset dataset = openDataset((dir / "sequence.txt").string());
  ASSERT_TRUE(dataset.camera_yaml.has_value());
  const Config config = loadConfig({*dataset.camera_yaml}).config;
  EXPECT_EQ(config.camera.image_width, 160);
  const double s = config.camera.mounting_height_m / config.camera.fx;
  const auto truth = readTum((dir / "groundtruth.tum").string());
  // The exact poses: the simulator is deterministic, so rebuild them in process.
  sim::SimulationSettings settings = smallSettings(sim::PathKind::random_walk, 12);
  const auto poses = sim::generatePath(settings.path);
  ASSERT_EQ(dataset.frames.size(), poses.size());
  ASSERT_EQ(truth.size(), poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    const Pose2 p = robotPoseFromMapHomography(*dataset.frames[i].map_from_image, config.camera.cx, config.camera.cy, s);
    EXPECT_NEAR(p.x, poses[i].x, 1e-9);
    EXPECT_NEAR(p.y, poses[i].y, 1e-9);
    EXPECT_NEAR(wrapAngle(p.theta - poses[i].theta), 0.0, 1e-9);
    EXPECT_NEAR(truth[i].T_world_robot.x, poses[i].x, 1e-9);
    EXPECT_NEAR(truth[i].T_world_robot.y, poses[i].y, 1e-9);
    const cv::Mat image = loadGrayImage(dataset.frames[i].image_path, 160, 120);
    EXPECT_GT(cv::mean(image)[0], 20.0);
  }
}

TEST(Simulator, IsDeterministicForASeedAndDiffersAcrossSeeds) {
  sim::SimulationSettings settings = smallSettings(sim::PathKind::loop, 5);
  settings.photometry.noise_sigma = 3.0;
  settings.mount_jitter_deg = 1.0;
  const cv::Mat a = sim::SequenceSimulator(settings).renderFrame(3);
  const cv::Mat b = sim::SequenceSimulator(settings).renderFrame(3);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  settings.seed = 2;
  EXPECT_GT(cv::norm(a, sim::SequenceSimulator(settings).renderFrame(3), cv::NORM_L1), 1000.0);
}

TEST(Simulator, RenderingIsGeometricallyConsistent) {
  // A ground point seen in two frames lands where the known motion says it should.
  sim::SimulationSettings settings = smallSettings(sim::PathKind::loop, 4);
  settings.camera = sim::scaledHdGroundIntrinsics(320, 240);
  settings.photometry.noise_sigma = 0.0;
  const sim::SequenceSimulator simulator(settings);
  const cv::Mat f0 = simulator.renderFrame(0), f2 = simulator.renderFrame(2);
  const Pose2 T_0_2 = between(simulator.groundTruth()[0], simulator.groundTruth()[2]);
  // Warp frame 2 into frame 0 through the ground plane and compare the overlap.
  cv::Mat map_x(f0.size(), CV_32F), map_y(f0.size(), CV_32F);
  for (int v = 0; v < f0.rows; ++v) {
    for (int u = 0; u < f0.cols; ++u) {
      const auto g0 = simulator.camera().pixelToGround({u, v});
      const auto px = simulator.camera().groundToPixel(T_0_2.inverse() * *g0);
      map_x.at<float>(v, u) = static_cast<float>(px->x());
      map_y.at<float>(v, u) = static_cast<float>(px->y());
    }
  }
  cv::Mat warped;
  cv::remap(f2, warped, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
  const cv::Rect inner(60, 40, 200, 160);
  cv::Mat diff;
  cv::absdiff(warped(inner), f0(inner), diff);
  EXPECT_LT(cv::mean(diff)[0], 4.0);  // grey levels; a misplaced image differs by tens
  cv::Mat unrelated;
  cv::absdiff(simulator.renderFrame(3)(inner), f0(inner), unrelated);
  EXPECT_GT(cv::mean(unrelated)[0], 3.0 * cv::mean(diff)[0]);
}

TEST(Paths, ShapesHaveTheirPromisedGeometry) {
  sim::PathSettings loop;
  loop.frames = 201;
  loop.laps = 2;
  const auto poses = sim::generatePath(loop);
  const double length = loop.step_m * 200;
  for (size_t i = 1; i < poses.size(); ++i) {
    EXPECT_NEAR((poses[i].translation() - poses[i - 1].translation()).norm(), loop.step_m, 1e-4);
  }
  // After one lap the robot is back near its start (the radius breathes by a few percent).
  EXPECT_LT((poses[100].translation() - poses[0].translation()).norm(), 0.05 * length / 2.0);

  sim::PathSettings mower;
  mower.kind = sim::PathKind::lawnmower;
  mower.frames = 200;
  mower.lane_length_m = 0.5;
  mower.lane_spacing_m = 0.08;
  const auto lanes = sim::generatePath(mower);
  // The second lane runs back, 8 cm to the left of the first: revisits at 180 degrees.
  const Pose2& back = lanes[static_cast<size_t>((0.5 + M_PI * 0.04 + 0.25) / 0.01)];
  EXPECT_NEAR(std::abs(back.theta), M_PI, 2e-3);  // sub-step integration rounds the U-turn's end
  EXPECT_NEAR(back.y, 0.08, 1e-3);

  sim::PathSettings walk;
  walk.kind = sim::PathKind::random_walk;
  walk.frames = 3000;
  walk.area_m = 0.5;
  for (const auto& p : sim::generatePath(walk)) EXPECT_LT(std::max(std::abs(p.x), std::abs(p.y)), 0.5);
}

TEST(Textures, KindsDifferAndWetGroundLooksDifferent) {
  const cv::Size size(200, 200);
  std::vector<cv::Mat> kinds;
  for (const auto& name : sim::textureKindNames()) {
    sim::TextureKind kind{};
    ASSERT_TRUE(sim::parseTextureKind(name, kind));
    kinds.push_back(sim::generateAlbedo(kind, size, 0.0003, 7));
    cv::Scalar mean, stddev;
    cv::meanStdDev(kinds.back(), mean, stddev);
    EXPECT_GT(stddev[0], 0.05) << name << " has too little texture";
  }
  EXPECT_GT(cv::norm(kinds[0], kinds[1], cv::NORM_L1), 1000.0);
  const cv::Mat wet = sim::wetAlbedo(kinds[0], 0.0003, 7);
  EXPECT_LT(cv::mean(wet)[0], 0.8 * cv::mean(kinds[0])[0]);
}

TEST(Simulator, FirstFrameIsMotionBlurredLikeTheRest) {
  // Sharpness (variance of the Laplacian) of frames 0, 1 and 2 of a blurred sequence: frame 0 must not be
  // the sharp one (it was, and odometry could not match it to the blurred frame 1).
  sim::SimulationSettings settings;
  settings.path.frames = 3;
  settings.motion_blur = 0.5;
  settings.photometry.noise_sigma = 0.0;
  const sim::SequenceSimulator simulator(settings);
  const auto sharpness = [&](int i) {
    cv::Mat laplacian;
    cv::Laplacian(simulator.renderFrame(i), laplacian, CV_64F);
    cv::Scalar mean, stddev;
    cv::meanStdDev(laplacian, mean, stddev);
    return stddev[0] * stddev[0];
  };
  const double s0 = sharpness(0), s1 = sharpness(1), s2 = sharpness(2);
  EXPECT_NEAR(s0 / s1, 1.0, 0.1);
  EXPECT_NEAR(s2 / s1, 1.0, 0.1);
  settings.motion_blur = 0.0;
  cv::Mat sharp_laplacian;
  cv::Laplacian(sim::SequenceSimulator(settings).renderFrame(0), sharp_laplacian, CV_64F);
  cv::Scalar mean, stddev;
  cv::meanStdDev(sharp_laplacian, mean, stddev);
  EXPECT_GT(stddev[0] * stddev[0], 1.2 * s0);  // and blur does lower it
}
