#include "groundslam/sim/Renderer.hpp"

#include <algorithm>

#include <opencv2/imgproc.hpp>

namespace groundslam::sim {

GroundRenderer::GroundRenderer(const CameraModel& camera, int supersampling)
    : camera_(camera), supersampling_(std::max(1, supersampling)) {
  const int w = camera.intrinsics().width * supersampling_, h = camera.intrinsics().height * supersampling_;
  std::vector<Eigen::Vector2d> pixels;
  pixels.reserve(static_cast<size_t>(w) * static_cast<size_t>(h));
  const double sub = 1.0 / supersampling_;
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      // Sub-pixel centres; pixel (u, v) covers [u - 0.5, u + 0.5] in OpenCV's convention.
      pixels.emplace_back((col + 0.5) * sub - 0.5, (row + 0.5) * sub - 0.5);
    }
  }
  rays_ = camera_.normalisedRays(pixels);
}

cv::Mat GroundRenderer::render(const GroundTexture& texture, const Pose2& T_world_robot,
                               const Eigen::Isometry3d& T_robot_camera, const GroundShadow& shadow) const {
  const int w = camera_.intrinsics().width * supersampling_, h = camera_.intrinsics().height * supersampling_;
  cv::Mat map_col(h, w, CV_32F), map_row(h, w, CV_32F);
  const bool shaded = shadow.darkness > 0.0;
  cv::Mat light = shaded ? cv::Mat(h, w, CV_32F) : cv::Mat();
  const Eigen::Matrix3d R = T_robot_camera.linear();
  const Eigen::Vector3d origin = T_robot_camera.translation();
  const double c = std::cos(T_world_robot.theta), s = std::sin(T_world_robot.theta);
  const double inv_texel = 1.0 / texture.texel_m;
  for (int row = 0; row < h; ++row) {
    float* col_ptr = map_col.ptr<float>(row);
    float* row_ptr = map_row.ptr<float>(row);
    for (int col = 0; col < w; ++col) {
      const Eigen::Vector2d& ray = rays_[static_cast<size_t>(row) * static_cast<size_t>(w) + static_cast<size_t>(col)];
      const Eigen::Vector3d d = R * Eigen::Vector3d(ray.x(), ray.y(), 1.0);
      const double t = d.z() < -1e-9 ? -origin.z() / d.z() : 1e6;  // rays above the horizon sample far away
      const double xr = origin.x() + t * d.x(), yr = origin.y() + t * d.y();
      const double xw = c * xr - s * yr + T_world_robot.x, yw = s * xr + c * yr + T_world_robot.y;
      col_ptr[col] = static_cast<float>((xw - texture.x_min_m) * inv_texel - 0.5);
      row_ptr[col] = static_cast<float>((texture.y_max_m - yw) * inv_texel - 0.5);
      if (shaded) {
        // Smoothstep across the penumbra: 0 in the light, 1 deep in the shadow.
        const double depth = (shadow.direction_robot.dot(Eigen::Vector2d(xr, yr)) - shadow.offset_m) / shadow.softness_m;
        const double u = std::clamp(0.5 + 0.5 * depth, 0.0, 1.0);
        light.ptr<float>(row)[col] = static_cast<float>(1.0 - shadow.darkness * u * u * (3.0 - 2.0 * u));
      }
    }
  }
  cv::Mat radiance;
  cv::remap(texture.albedo, radiance, map_col, map_row, cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
  if (shaded) radiance = radiance.mul(light);
  if (supersampling_ > 1) {
    cv::resize(radiance, radiance, cv::Size(camera_.intrinsics().width, camera_.intrinsics().height), 0, 0, cv::INTER_AREA);
  }
  return radiance;
}

}  // namespace groundslam::sim
