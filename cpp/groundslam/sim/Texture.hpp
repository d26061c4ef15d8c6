#pragma once
// Ground textures for the simulator: seeded procedural kinds and user images, with their metric size.

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace groundslam::sim {

enum class TextureKind { asphalt, concrete, carpet, tiles };

const std::vector<std::string>& textureKindNames();
/// Parses a kind name; returns false for an unknown name.
bool parseTextureKind(const std::string& name, TextureKind& kind);
std::string textureKindName(TextureKind kind);

/// A texture laid on the world plane: texel (col, row) covers the world point
/// (x_min + (col + 0.5) texel_m, y_max - (row + 0.5) texel_m). Rows run along world -y, like a map image.
struct GroundTexture {
  cv::Mat albedo;        ///< CV_32F, brightness in [0, 1]
  double texel_m = 0.0;  ///< metres per texel
  double x_min_m = 0.0;  ///< world x of the left edge
  double y_max_m = 0.0;  ///< world y of the top edge
};

/// Generates a procedural texture of `size` texels. Deterministic for a given seed.
cv::Mat generateAlbedo(TextureKind kind, cv::Size size, double texel_m, std::uint64_t seed);

/// The same ground after rain: darker, more contrast, smooth dark puddles.
cv::Mat wetAlbedo(const cv::Mat& dry, double texel_m, std::uint64_t seed);

}  // namespace groundslam::sim
