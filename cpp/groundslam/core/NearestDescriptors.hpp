#pragma once
// The two nearest train descriptors of every query descriptor (256-bit, Hamming distance), comparing every
// pair: the heart of brute-force matching. The same answer on every CPU; where the CPU has vector popcount
// (AVX-512 VPOPCNTDQ) or byte shuffles (AVX2), eight or four pairs are compared per instruction sequence.

#include <vector>

#include <opencv2/core.hpp>

namespace groundslam {

struct TwoNearest {
  int best = -1;             ///< train row of the nearest descriptor (the lowest row among equals); -1: no train row
  int best_distance = 257;   ///< its Hamming distance, bits
  int second_distance = 257;  ///< the second smallest distance among all train rows (equal to best's when tied); 257: none
};

/// How the pairs are compared. `automatic`: the fastest the running CPU supports.
enum class HammingKernel { automatic, scalar, avx2, avx512 };

/// The kernels the running CPU supports (scalar always), slowest first.
std::vector<HammingKernel> supportedHammingKernels();

/// One TwoNearest per query row (CV_8U, 32 columns each). Throws std::invalid_argument for a kernel the CPU
/// does not support or descriptors that are not 32-byte rows.
std::vector<TwoNearest> twoNearest(const cv::Mat& query, const cv::Mat& train, HammingKernel kernel = HammingKernel::automatic);

}  // namespace groundslam
