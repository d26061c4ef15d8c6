#include "groundslam/sim/Texture.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace groundslam::sim {
namespace {

/// Smooth value noise in [-1, 1] with features about `cell_m` across.
cv::Mat valueNoise(cv::Size size, double cell_m, double texel_m, cv::RNG& rng) {
  const double cell_texels = std::max(1.0, cell_m / texel_m);
  const int grid_w = static_cast<int>(std::ceil(size.width / cell_texels)) + 3;
  const int grid_h = static_cast<int>(std::ceil(size.height / cell_texels)) + 3;
  cv::Mat grid(grid_h, grid_w, CV_32F);
  rng.fill(grid, cv::RNG::UNIFORM, -1.0, 1.0);
  if (cell_texels <= 1.0) return grid(cv::Rect(0, 0, size.width, size.height)).clone();
  cv::Mat noise;
  const cv::Size scaled(static_cast<int>(grid_w * cell_texels), static_cast<int>(grid_h * cell_texels));
  cv::resize(grid, noise, scaled, 0, 0, cv::INTER_CUBIC);
  return noise(cv::Rect(0, 0, size.width, size.height)).clone();
}

/// Per-texel grain, blurred to `grain_m`.
cv::Mat grain(cv::Size size, double grain_m, double texel_m, cv::RNG& rng) {
  cv::Mat g(size, CV_32F);
  rng.fill(g, cv::RNG::NORMAL, 0.0, 1.0);
  const double sigma = grain_m / texel_m;
  if (sigma > 0.3) cv::GaussianBlur(g, g, cv::Size(0, 0), sigma);
  cv::normalize(g, g, -1.0, 1.0, cv::NORM_MINMAX);
  return g;
}

int countFor(cv::Size size, double texel_m, double per_square_metre) {
  const double area_m2 = size.area() * texel_m * texel_m;
  return static_cast<int>(area_m2 * per_square_metre);
}

cv::Point randomPoint(cv::Size size, cv::RNG& rng) { return {rng.uniform(0, size.width), rng.uniform(0, size.height)}; }

/// Irregular convex-ish polygons (stones, aggregate) of radius in [r_min_m, r_max_m].
void drawStones(cv::Mat& image, int count, double r_min_m, double r_max_m, double texel_m, float lo, float hi,
                cv::RNG& rng) {
  std::vector<cv::Point> polygon;
  for (int i = 0; i < count; ++i) {
    const cv::Point centre = randomPoint(image.size(), rng);
    const double radius = rng.uniform(r_min_m, r_max_m) / texel_m;
    const int vertices = rng.uniform(5, 10);
    const double rotation = rng.uniform(0.0, 2.0 * M_PI);
    polygon.clear();
    for (int k = 0; k < vertices; ++k) {
      const double a = rotation + 2.0 * M_PI * k / vertices;
      const double r = radius * rng.uniform(0.6, 1.0);
      polygon.emplace_back(centre.x + static_cast<int>(std::lround(r * std::cos(a))),
                           centre.y + static_cast<int>(std::lround(r * std::sin(a))));
    }
    cv::fillConvexPoly(image, polygon, cv::Scalar(rng.uniform(lo, hi)), cv::LINE_AA);
  }
}

void drawDots(cv::Mat& image, int count, double r_min_m, double r_max_m, double texel_m, float lo, float hi,
              cv::RNG& rng) {
  for (int i = 0; i < count; ++i) {
    const int radius = std::max(1, static_cast<int>(std::lround(rng.uniform(r_min_m, r_max_m) / texel_m)));
    cv::circle(image, randomPoint(image.size(), rng), radius, cv::Scalar(rng.uniform(lo, hi)), cv::FILLED, cv::LINE_AA);
  }
}

cv::Mat asphalt(cv::Size size, double texel_m, cv::RNG& rng) {
  cv::Mat image = 0.3f + 0.06f * valueNoise(size, 0.01, texel_m, rng) + 0.05f * grain(size, 0.0003, texel_m, rng);
  drawStones(image, countFor(size, texel_m, 4.0e4), 0.0008, 0.004, texel_m, 0.35f, 0.9f, rng);
  image += 0.07f * grain(size, 0.0002, texel_m, rng);
  return image;
}

cv::Mat concrete(cv::Size size, double texel_m, cv::RNG& rng) {
  cv::Mat image = 0.6f + 0.08f * valueNoise(size, 0.03, texel_m, rng) + 0.06f * valueNoise(size, 0.004, texel_m, rng);
  image += 0.08f * grain(size, 0.0004, texel_m, rng);
  drawDots(image, countFor(size, texel_m, 6.0e4), 0.0002, 0.0009, texel_m, 0.15f, 0.4f, rng);
  drawDots(image, countFor(size, texel_m, 3.0e4), 0.0002, 0.0006, texel_m, 0.75f, 0.95f, rng);
  return image;
}

cv::Mat carpet(cv::Size size, double texel_m, cv::RNG& rng) {
  // Two fibre directions in patches (tufts), box-blurred noise along each direction.
  const int fibre = std::max(3, static_cast<int>(0.003 / texel_m));
  cv::Mat along_x, along_y;
  cv::blur(grain(size, 0.0, texel_m, rng), along_x, cv::Size(fibre, 1));
  cv::blur(grain(size, 0.0, texel_m, rng), along_y, cv::Size(1, fibre));
  cv::Mat mask = valueNoise(size, 0.006, texel_m, rng) > 0.0f;
  cv::Mat fibres = along_y.clone();
  along_x.copyTo(fibres, mask);
  cv::normalize(fibres, fibres, -1.0, 1.0, cv::NORM_MINMAX);
  cv::Mat image = 0.5f + 0.35f * fibres + 0.1f * valueNoise(size, 0.02, texel_m, rng);
  const int strands = countFor(size, texel_m, 4.0e4);
  for (int i = 0; i < strands; ++i) {
    const cv::Point a = randomPoint(size, rng);
    const double angle = rng.uniform(0.0, 2.0 * M_PI), length = rng.uniform(0.002, 0.006) / texel_m;
    const cv::Point b(a.x + static_cast<int>(length * std::cos(angle)), a.y + static_cast<int>(length * std::sin(angle)));
    cv::line(image, a, b, cv::Scalar(rng.uniform(0.1f, 0.95f)), 1, cv::LINE_AA);
  }
  return image;
}

cv::Mat tiles(cv::Size size, double texel_m, cv::RNG& rng) {
  // Every tile carries the same speckle pattern (the hard, repetitive case), with faint unique dirt.
  const int tile = std::max(8, static_cast<int>(0.04 / texel_m));
  const int grout = std::max(1, static_cast<int>(0.002 / texel_m));
  cv::Mat pattern = 0.65f + 0.12f * valueNoise({tile, tile}, 0.004, texel_m, rng);
  drawDots(pattern, countFor({tile, tile}, texel_m, 2.0e4), 0.0003, 0.0012, texel_m, 0.3f, 0.5f, rng);
  cv::Mat image(size, CV_32F);
  for (int y = 0; y < size.height; y += tile) {
    for (int x = 0; x < size.width; x += tile) {
      const cv::Rect cell = cv::Rect(x, y, tile, tile) & cv::Rect(0, 0, size.width, size.height);
      image(cell) = pattern(cv::Rect(0, 0, cell.width, cell.height)) + rng.uniform(-0.04f, 0.04f);
    }
  }
  image += 0.03f * grain(size, 0.0003, texel_m, rng);
  drawDots(image, countFor(size, texel_m, 2.0e3), 0.0003, 0.0015, texel_m, 0.35f, 0.55f, rng);
  for (int p = 0; p < size.width; p += tile) cv::rectangle(image, {p, 0}, {p + grout - 1, size.height}, 0.2, cv::FILLED);
  for (int p = 0; p < size.height; p += tile) cv::rectangle(image, {0, p}, {size.width, p + grout - 1}, 0.2, cv::FILLED);
  return image;
}

}  // namespace

const std::vector<std::string>& textureKindNames() {
  static const std::vector<std::string> names = {"asphalt", "concrete", "carpet", "tiles"};
  return names;
}

bool parseTextureKind(const std::string& name, TextureKind& kind) {
  const auto& names = textureKindNames();
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) return false;
  kind = static_cast<TextureKind>(it - names.begin());
  return true;
}

std::string textureKindName(TextureKind kind) { return textureKindNames()[static_cast<size_t>(kind)]; }

cv::Mat generateAlbedo(TextureKind kind, cv::Size size, double texel_m, std::uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat image;
  switch (kind) {
    case TextureKind::asphalt: image = asphalt(size, texel_m, rng); break;
    case TextureKind::concrete: image = concrete(size, texel_m, rng); break;
    case TextureKind::carpet: image = carpet(size, texel_m, rng); break;
    case TextureKind::tiles: image = tiles(size, texel_m, rng); break;
  }
  cv::min(cv::max(image, 0.0), 1.0, image);
  return image;
}

cv::Mat wetAlbedo(const cv::Mat& dry, double texel_m, std::uint64_t seed) {
  cv::RNG rng(seed ^ 0x5eedULL);
  cv::Mat wet;
  cv::pow(dry, 1.6, wet);  // wet surfaces darken and gain contrast
  wet = 0.05f + 0.7f * wet;
  cv::Mat smooth;
  cv::GaussianBlur(wet, smooth, cv::Size(0, 0), std::max(1.0, 0.0006 / texel_m));
  const cv::Mat puddles = valueNoise(dry.size(), 0.05, texel_m, rng) > 0.45f;
  const cv::Mat darker = 0.6f * smooth;
  darker.copyTo(wet, puddles);
  return wet;
}

}  // namespace groundslam::sim
