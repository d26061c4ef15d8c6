// Outdoor robustness: the camera's tilt and height recovered from two views of the ground, and features
// that stay still in the image while the robot moves kept out of the motion.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "groundslam/core/CameraModel.hpp"
#include "groundslam/core/MountEstimation.hpp"

using namespace groundslam;

namespace {

constexpr double kDeg = M_PI / 180.0;

CameraIntrinsics hdGroundAt320() {
  CameraIntrinsics k;
  k.width = 320, k.height = 240;
  k.fx = 439.14, k.fy = 439.11, k.cx = 164.1, k.cy = 121.2;
  return k;
}

struct RayPairs {
  std::vector<Eigen::Vector2d> reference, current;
};

/// Ground points seen by two cameras in known states and poses; pixel noise of `noise_px`.
RayPairs observe(const MountState& reference_state, const MountState& current_state, const Pose2& T_reference_current,
                 double noise_px, unsigned seed) {
  const CameraIntrinsics k = hdGroundAt320();
  const Eigen::Isometry3d calibrated = defaultCameraMount(0.25);
  const CameraModel reference(k, mountFor(calibrated, reference_state)), current(k, mountFor(calibrated, current_state));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(-0.12, 0.12), uy(-0.1, 0.1);
  std::normal_distribution<double> noise(0.0, noise_px);
  const auto ray = [&](const Eigen::Vector2d& pixel) {
    return Eigen::Vector2d((pixel.x() + noise(rng) - k.cx) / k.fx, (pixel.y() + noise(rng) - k.cy) / k.fy);
  };
  const auto inside = [&](const Eigen::Vector2d& p) { return p.x() >= 0 && p.y() >= 0 && p.x() < k.width && p.y() < k.height; };
  RayPairs pairs;
  while (pairs.reference.size() < 400) {
    const Eigen::Vector2d ground_reference(ux(rng), uy(rng));  // in the reference robot frame
    const Eigen::Vector2d ground_current = T_reference_current.inverse() * ground_reference;
    const auto a = reference.groundToPixel(ground_reference), b = current.groundToPixel(ground_current);
    if (!a || !b || !inside(*a) || !inside(*b)) continue;
    pairs.reference.push_back(ray(*a));
    pairs.current.push_back(ray(*b));
  }
  return pairs;
}

}  // namespace

TEST(MountEstimation, RecoversTiltAndHeightOfATiltedCamera) {
  const MountState reference{0.4 * kDeg, -0.3 * kDeg, 0.25};
  const MountState truth{-0.5 * kDeg, 0.35 * kDeg, 0.2515};
  const Pose2 motion(0.045, 0.012, 0.08);
  // 0.1 px of keypoint noise: a tilt of 0.1 degrees moves the ground points by 0.4 mm, 0.8 px.
  const RayPairs pairs = observe(reference, truth, motion, 0.1, 7);
  const MountEstimate estimate = estimateMount(pairs.reference, pairs.current, defaultCameraMount(0.25), reference, Pose2(), {});
  ASSERT_TRUE(estimate.ok);
  EXPECT_NEAR(estimate.current.roll_rad / kDeg, -0.5, 0.1);
  EXPECT_NEAR(estimate.current.pitch_rad / kDeg, 0.35, 0.1);
  EXPECT_NEAR(estimate.current.height_m, 0.2515, 0.0002);
  EXPECT_NEAR(estimate.T_reference_current.x, motion.x, 0.0004);
  EXPECT_NEAR(estimate.T_reference_current.y, motion.y, 0.0004);
  EXPECT_NEAR(estimate.T_reference_current.theta / kDeg, motion.theta / kDeg, 0.02);
  // Ignoring the tilt, the same rays give a motion millimetres off: what the estimate removes.
  const MountEstimate level = estimateMount(pairs.reference, pairs.current, defaultCameraMount(0.25), MountState{0.0, 0.0, 0.25},
                                            Pose2(), MountEstimationSettings{1e-9, 1e-9, 1e-9, 0.0002, 300, 30});
  ASSERT_TRUE(level.ok);
  EXPECT_GT((level.T_reference_current.translation() - motion.translation()).norm(), 0.002);
}

TEST(MountEstimation, StraightCameraStaysStraight) {
  const MountState level{0.0, 0.0, 0.25};
  const RayPairs pairs = observe(level, level, Pose2(0.03, -0.01, -0.2), 0.1, 11);
  const MountEstimate estimate = estimateMount(pairs.reference, pairs.current, defaultCameraMount(0.25), level, Pose2(), {});
  ASSERT_TRUE(estimate.ok);
  EXPECT_NEAR(estimate.current.roll_rad / kDeg, 0.0, 0.1);
  EXPECT_NEAR(estimate.current.pitch_rad / kDeg, 0.0, 0.1);
  EXPECT_NEAR(estimate.current.height_m, 0.25, 0.0002);
}

TEST(MountEstimation, TooFewPairsIsNoEstimate) {
  const MountState level{0.0, 0.0, 0.25};
  RayPairs pairs = observe(level, level, Pose2(0.03, 0.0, 0.0), 0.3, 3);
  pairs.reference.resize(10);
  pairs.current.resize(10);
  EXPECT_FALSE(estimateMount(pairs.reference, pairs.current, defaultCameraMount(0.25), level, Pose2(), {}).ok);
}
