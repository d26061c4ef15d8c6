#include <cmath>

#include <gtest/gtest.h>

#include "groundslam/core/Pose2.hpp"

using groundslam::between;
using groundslam::Pose2;
using groundslam::wrapAngle;

namespace {

void expectPoseNear(const Pose2& a, const Pose2& b, double tol = 1e-12) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(wrapAngle(a.theta - b.theta), 0.0, tol);
}

}  // namespace

TEST(WrapAngle, MapsIntoHalfOpenIntervalAroundZero) {
  EXPECT_DOUBLE_EQ(wrapAngle(M_PI), M_PI);
  EXPECT_DOUBLE_EQ(wrapAngle(-M_PI), M_PI);  // -pi and pi are the same angle; we keep +pi
  EXPECT_NEAR(wrapAngle(3.0 * M_PI), M_PI, 1e-12);
  EXPECT_NEAR(wrapAngle(-3.0 * M_PI + 1e-9), -M_PI + 1e-9, 1e-12);
  EXPECT_NEAR(wrapAngle(2.0 * M_PI + 0.25), 0.25, 1e-12);
  EXPECT_NEAR(wrapAngle(-7.0), -7.0 + 2.0 * M_PI, 1e-12);
}

TEST(Pose2, ComposeMatchesMatrixProduct) {
  const Pose2 a(1.0, -2.0, 0.7), b(-0.3, 0.5, 2.9);
  const Eigen::Matrix3d expected = a.matrix() * b.matrix();
  const Pose2 c = a * b;
  EXPECT_TRUE(c.matrix().isApprox(expected, 1e-12));
  EXPECT_NEAR(c.theta, wrapAngle(0.7 + 2.9), 1e-12);  // 3.6 rad wraps below -pi/... into (-pi, pi]
}

TEST(Pose2, InverseAndIdentity) {
  const Pose2 a(0.4, 1.5, -2.2);
  expectPoseNear(a * a.inverse(), Pose2::identity());
  expectPoseNear(a.inverse() * a, Pose2::identity());
  expectPoseNear(a.inverse().inverse(), a);
  const Eigen::Vector2d p(0.3, -0.8);
  EXPECT_TRUE((a.inverse() * (a * p)).isApprox(p, 1e-12));
}

TEST(Pose2, BetweenRecoversRelativeMotion) {
  const Pose2 T_w_a(1.0, 2.0, 3.0), T_a_b(0.25, -0.1, 0.4);
  const Pose2 T_w_b = T_w_a * T_a_b;
  expectPoseNear(between(T_w_a, T_w_b), T_a_b);
}

TEST(Pose2, AnglesAtPlusMinusPi) {
  // Two half turns make a full turn; composing across the +-pi seam stays continuous.
  const Pose2 half(0.0, 0.0, M_PI), minus_half(0.0, 0.0, -M_PI);
  expectPoseNear(half * half, Pose2::identity());
  expectPoseNear(half * minus_half, Pose2::identity());
  const Pose2 a(1.0, 0.0, M_PI - 1e-6), b(0.0, 0.0, 2e-6);
  EXPECT_NEAR((a * b).theta, -M_PI + 1e-6, 1e-12);
  const Pose2 rel = between(Pose2(0, 0, M_PI - 0.01), Pose2(0, 0, -M_PI + 0.01));
  EXPECT_NEAR(rel.theta, 0.02, 1e-12);
  // A point rotated by pi about the origin lands opposite.
  const Eigen::Vector2d p = half * Eigen::Vector2d(1.0, 2.0);
  EXPECT_NEAR(p.x(), -1.0, 1e-12);
  EXPECT_NEAR(p.y(), -2.0, 1e-12);
}

TEST(Pose2, MatrixRoundTrip) {
  const Pose2 a(-3.0, 0.125, -3.1);
  expectPoseNear(Pose2::fromMatrix(a.matrix()), a);
}
