#include "groundslam/sim/Simulator.hpp"

#include <stdexcept>
#include <string>

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace groundslam::sim {
namespace {

constexpr int kMaxTextureSide = 8192;  // texels; bounds the memory of a texture to 256 MB

int supersamplingFor(const CameraIntrinsics& camera) { return camera.width <= 800 ? 2 : 1; }

}  // namespace

CameraIntrinsics scaledHdGroundIntrinsics(int width, int height) {
  // HD Ground: 1600x1200, fx = 2195.70853, fy = 2195.56073, cx = 820.7289683, cy = 606.242723.
  const double scale = width / 1600.0;
  CameraIntrinsics k;
  k.width = width;
  k.height = height;
  k.fx = 2195.70853 * scale;
  k.fy = 2195.56073 * scale;
  k.cx = 0.5 * width + (820.7289683 - 800.0) * scale;
  k.cy = 0.5 * height + (606.242723 - 600.0) * scale;
  return k;
}

SequenceSimulator::SequenceSimulator(const SimulationSettings& settings, const cv::Mat& user_texture)
    : settings_(settings),
      camera_(settings.camera, defaultCameraMount(settings.mounting_height_m)),
      poses_(generatePath(settings.path)),
      renderer_(camera_, supersamplingFor(settings.camera)) {
  cv::RNG rng(settings.seed * 31ULL + 2ULL);
  const double sigma = settings.mount_jitter_deg * M_PI / 180.0, keep = 0.8;
  Eigen::Vector2d jitter(rng.gaussian(sigma), rng.gaussian(sigma));
  for (size_t i = 0; i < poses_.size(); ++i) {
    jitter_rad_.push_back(jitter);
    // AR(1) with stationary standard deviation sigma: the mount rocks smoothly.
    const double innovation = sigma * std::sqrt(1.0 - keep * keep);
    jitter = keep * jitter + Eigen::Vector2d(rng.gaussian(innovation), rng.gaussian(innovation));
  }
  cv::RNG height_rng(settings.seed * 131ULL + 5ULL);  // its own stream: earlier sequences stay as they were
  double dh = height_rng.gaussian(settings.height_jitter_m);
  for (size_t i = 0; i < poses_.size(); ++i) {
    height_jitter_m_.push_back(dh);
    dh = keep * dh + height_rng.gaussian(settings.height_jitter_m * std::sqrt(1.0 - keep * keep));
  }
  addHardMotion();
  prepareArtifacts();
  dry_ = layTexture(user_texture);
  wet_ = dry_;
  if (settings.wet_after < 1.0) wet_.albedo = wetAlbedo(dry_.albedo, dry_.texel_m, settings.seed);
}

void SequenceSimulator::addHardMotion() {
  const int period = settings_.motion.spin_every;
  spin_rad_.assign(poses_.size(), 0.0);
  if (period <= 0) return;
  // A square wave on the heading: the camera (above the robot's origin) turns on the spot, the path stays.
  for (size_t i = 0; i < poses_.size(); ++i) {
    const double spin = static_cast<int>(i) % period >= (period + 1) / 2 ? settings_.motion.spin_deg * M_PI / 180.0 : 0.0;
    poses_[i].theta = wrapAngle(poses_[i].theta + spin);
    spin_rad_[i] = spin;
  }
}

void SequenceSimulator::prepareArtifacts() {
  const CameraArtifacts& a = settings_.artifacts;
  const auto& k = settings_.camera;
  cv::RNG rng(settings_.seed * 257ULL + 11ULL);
  const double sun = rng.uniform(0.0, 2.0 * M_PI);
  sun_direction_world_ = Eigen::Vector2d(std::cos(sun), std::sin(sun));
  // The edge passes a third of the footprint's radius from its centre: the shadow covers about a quarter.
  shadow_offset_m_ = 0.35 * cornerRadius();
  const double scale = k.width / 320.0;
  if (a.lens_dirt > 0) {
    dirt_ = cv::Mat(k.height, k.width, CV_32F, cv::Scalar(1.0f));
    for (int b = 0; b < a.lens_dirt; ++b) {
      const double u = rng.uniform(0.1, 0.9) * k.width, v = rng.uniform(0.1, 0.9) * k.height;
      // Opaque specks of mud with a sharp rim, and large soft smudges.
      const bool speck = b % 2 == 0;
      const double radius = scale * (speck ? rng.uniform(2.0, 5.0) : rng.uniform(6.0, 14.0));
      const double opacity = speck ? rng.uniform(0.85, 0.95) : rng.uniform(0.3, 0.6);
      const double rim = speck ? 0.7 * scale : 0.5 * radius;
      const double reach = radius + 3.0 * rim;
      for (int row = std::max(0, static_cast<int>(v - reach)); row < std::min(k.height, static_cast<int>(v + reach) + 1); ++row) {
        for (int col = std::max(0, static_cast<int>(u - reach)); col < std::min(k.width, static_cast<int>(u + reach) + 1); ++col) {
          const double r = std::hypot(col - u, row - v);
          const double cover = 1.0 / (1.0 + std::exp((r - radius) / rim));  // 1 inside, 0 outside, smooth rim
          dirt_.at<float>(row, col) *= static_cast<float>(1.0 - opacity * cover);
        }
      }
    }
  }
  if (a.bumper > 0.0) {
    // A dark plate along the bottom of the image with a rough edge and bright bolts: it never moves.
    bumper_ = cv::Mat(k.height, k.width, CV_32F, cv::Scalar(0.15f));
    bumper_cover_ = cv::Mat::zeros(k.height, k.width, CV_32F);
    const double top = (1.0 - a.bumper) * k.height;
    for (int col = 0; col < k.width; ++col) {
      const double edge = top + 2.0 * scale * std::sin(col * 0.21 / scale) + 1.5 * scale * std::sin(col * 0.057 / scale);
      for (int row = std::max(0, static_cast<int>(edge) - 2); row < k.height; ++row) {
        bumper_cover_.at<float>(row, col) = static_cast<float>(std::clamp(row - edge + 0.5, 0.0, 1.0));
      }
    }
    for (int bolt = 0; bolt < 12; ++bolt) {
      const double u = rng.uniform(0.05, 0.95) * k.width, v = rng.uniform(top + 3.0 * scale, static_cast<double>(k.height));
      cv::circle(bumper_, cv::Point(static_cast<int>(u), static_cast<int>(v)), std::max(1, static_cast<int>(2.5 * scale)),
                 cv::Scalar(0.9), cv::FILLED);
      cv::rectangle(bumper_, cv::Rect(static_cast<int>(u + 6 * scale), static_cast<int>(v), static_cast<int>(5 * scale) + 1,
                                      static_cast<int>(3 * scale) + 1), cv::Scalar(0.6), cv::FILLED);
    }
  }
  if (a.glare > 0.0) {
    glare_ = cv::Mat(k.height, k.width, CV_32F);
    const double u = rng.uniform(0.25, 0.75) * k.width, v = rng.uniform(0.25, 0.75) * k.height, sigma = 0.1 * k.width;
    for (int row = 0; row < k.height; ++row) {
      for (int col = 0; col < k.width; ++col) {
        const double r2 = ((col - u) * (col - u) + (row - v) * (row - v)) / (sigma * sigma);
        glare_.at<float>(row, col) = static_cast<float>(a.glare * std::exp(-0.5 * r2));
      }
    }
  }
}

GroundShadow SequenceSimulator::shadowAt(const Pose2& pose) const {
  GroundShadow shadow;
  shadow.darkness = settings_.artifacts.shadow;
  shadow.direction_robot = Eigen::Rotation2Dd(-pose.theta) * sun_direction_world_;  // the sun stays, the robot turns
  shadow.offset_m = shadow_offset_m_;
  shadow.softness_m = 0.0015;  // the sun's half degree over the body's height above the ground
  return shadow;
}

double SequenceSimulator::cornerRadius() const {
  const auto& k = settings_.camera;
  double radius = 0.0;
  for (const Eigen::Vector2d& corner : {Eigen::Vector2d(0, 0), Eigen::Vector2d(k.width, 0), Eigen::Vector2d(0, k.height),
                                       Eigen::Vector2d(k.width, k.height)}) {
    if (const auto p = camera_.pixelToGround(corner)) radius = std::max(radius, p->norm());
  }
  return radius;
}

double SequenceSimulator::footprintRadius() const {
  const double jitter_m = settings_.mounting_height_m * std::tan(4.0 * settings_.mount_jitter_deg * M_PI / 180.0);
  const double height_m = 4.0 * settings_.height_jitter_m / settings_.mounting_height_m * cornerRadius();
  return 1.1 * cornerRadius() + jitter_m + height_m + 0.01;
}

GroundTexture SequenceSimulator::layTexture(const cv::Mat& user_texture) const {
  double x_min = 1e9, x_max = -1e9, y_min = 1e9, y_max = -1e9;
  for (const Pose2& p : poses_) {
    x_min = std::min(x_min, p.x);
    x_max = std::max(x_max, p.x);
    y_min = std::min(y_min, p.y);
    y_max = std::max(y_max, p.y);
  }
  const double margin = footprintRadius();
  x_min -= margin, x_max += margin, y_min -= margin, y_max += margin;
  if (settings_.ground_seed) {
    const double half = 0.5 * settings_.ground_size_m;
    if (x_min < -half || x_max > half || y_min < -half || y_max > half) {
      throw std::invalid_argument("the path leaves the ground square of " + std::to_string(settings_.ground_size_m) +
                                  " m around the origin; make the ground larger");
    }
    x_min = y_min = -half;
    x_max = y_max = half;
  }
  GroundTexture texture;
  if (!user_texture.empty()) {
    user_texture.convertTo(texture.albedo, CV_32F, 1.0 / 255.0);
    texture.texel_m = settings_.user_texture_width_m / user_texture.cols;
    // Centre the image on the path; beyond its edges the renderer mirrors it.
    texture.x_min_m = 0.5 * (x_min + x_max) - 0.5 * settings_.user_texture_width_m;
    texture.y_max_m = 0.5 * (y_min + y_max) + 0.5 * texture.texel_m * user_texture.rows;
    return texture;
  }
  const double extent = std::max(x_max - x_min, y_max - y_min);
  texture.texel_m = std::max(camera_.groundSampleDistance() / supersamplingFor(settings_.camera),
                             extent / kMaxTextureSide);
  texture.x_min_m = x_min;
  texture.y_max_m = y_max;
  const cv::Size size(static_cast<int>(std::ceil((x_max - x_min) / texture.texel_m)),
                      static_cast<int>(std::ceil((y_max - y_min) / texture.texel_m)));
  TextureKind kind = TextureKind::asphalt;
  parseTextureKind(settings_.texture_kind, kind);
  texture.albedo = generateAlbedo(kind, size, texture.texel_m, settings_.ground_seed.value_or(settings_.seed));
  return texture;
}

Eigen::Vector3d SequenceSimulator::mountStateAt(int index) const {
  const Eigen::Vector2d& j = jitter_rad_[static_cast<size_t>(index)];
  return Eigen::Vector3d(j.x(), j.y(), settings_.mounting_height_m + height_jitter_m_[static_cast<size_t>(index)]);
}

Eigen::Isometry3d SequenceSimulator::mountAt(int index) const {
  const Eigen::Vector2d& j = jitter_rad_[static_cast<size_t>(index)];
  Eigen::Isometry3d T = defaultCameraMount(mountStateAt(index).z());
  T.linear() = (Eigen::AngleAxisd(j.x(), Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(j.y(), Eigen::Vector3d::UnitY()))
                   .toRotationMatrix() *
               T.linear();
  return T;
}

cv::Mat SequenceSimulator::renderFrame(int index) const {
  const bool wet = index >= static_cast<int>(settings_.wet_after * frameCount());
  const GroundTexture& texture = wet ? wet_ : dry_;
  const Pose2& pose = poses_[static_cast<size_t>(index)];
  const Eigen::Isometry3d mount = mountAt(index);
  cv::Mat radiance;
  if (settings_.motion_blur > 0.0 && frameCount() > 1) {
    // Average renders over the exposure, centred on this frame's pose: cameras stamp mid-exposure. The
    // first frame is blurred by the motion towards the second: a moving camera's first image is not sharp.
    const size_t i = static_cast<size_t>(index);
    // The blur follows the path; a sharp turn happens between exposures.
    const auto unspun = [&](size_t k) { return Pose2(poses_[k].x, poses_[k].y, poses_[k].theta - spin_rad_[k]); };
    const Pose2 path_motion = index > 0 ? between(unspun(i - 1), unspun(i)) : between(unspun(i), unspun(i + 1));
    const Eigen::Vector2d shift = Eigen::Rotation2Dd(-spin_rad_[i]) * path_motion.translation();
    const Pose2 motion(shift.x(), shift.y(), path_motion.theta);
    const double blur_px = settings_.motion_blur * motion.translation().norm() / camera_.groundSampleDistance();
    const int samples = std::clamp(static_cast<int>(std::ceil(blur_px)) + 1, 2, 12);
    radiance = cv::Mat::zeros(settings_.camera.height, settings_.camera.width, CV_32F);
    for (int k = 0; k < samples; ++k) {
      const double u = settings_.motion_blur * (static_cast<double>(k) / (samples - 1) - 0.5);
      const Pose2 sub = pose * Pose2(u * motion.x, u * motion.y, u * motion.theta);
      radiance += renderer_.render(texture, sub, mount, shadowAt(sub));
    }
    radiance /= samples;
  } else {
    radiance = renderer_.render(texture, pose, mount, shadowAt(pose));
  }
  if (!dirt_.empty()) radiance = radiance.mul(dirt_);
  if (!glare_.empty()) radiance += glare_;
  if (!bumper_.empty()) radiance = radiance.mul(1.0 - bumper_cover_) + bumper_.mul(bumper_cover_);
  return expose(radiance, settings_.photometry, index, settings_.seed);
}

std::vector<bool> droppedFrames(int frames, double probability, int max_gap, std::uint64_t seed) {
  std::vector<bool> dropped(static_cast<size_t>(std::max(0, frames)), false);
  if (probability <= 0.0 || max_gap < 1) return dropped;
  cv::RNG rng(seed * 613ULL + 17ULL);
  for (int i = 1; i + 1 < frames; ++i) {
    if (rng.uniform(0.0, 1.0) >= probability) continue;
    const int gap = rng.uniform(1, max_gap + 1);
    for (int k = 0; k < gap && i + 1 < frames; ++k, ++i) dropped[static_cast<size_t>(i)] = true;
  }
  return dropped;
}

}  // namespace groundslam::sim
