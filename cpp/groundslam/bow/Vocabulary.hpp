#pragma once
// A vocabulary tree for binary descriptors (Nister & Stewenius 2006; Galvez-Lopez & Tardos 2012):
// hierarchical k-medians in Hamming space with k-means++ seeding, TF-IDF weighted words.

#include <array>
#include <cstdint>
#include <utility>
#include <string>
#include <functional>
#include <vector>

#include <opencv2/core.hpp>

namespace groundslam {

using Descriptor = std::array<std::uint8_t, 32>;  ///< one 256-bit ORB descriptor

/// Sparse bag-of-words vector: (word id, weight) sorted by word id, L1-normalised. A sorted vector, not a
/// map: every frame keeps one, and a map's nodes would cost four times the memory.
using BowVector = std::vector<std::pair<int, float>>;

struct VocabularySettings {
  int branching = 10;  ///< children per node (k)
  int depth = 4;       ///< levels below the root (L); up to k^L words
  int iterations = 10; ///< k-medians refinement rounds per node
  std::uint64_t seed = 1;
};

class Vocabulary {
 public:
  struct Node {
    Descriptor centre{};
    int first_child = -1;  ///< index of the first child; children are consecutive
    int child_count = 0;
    int word = -1;         ///< word id of a leaf, -1 for inner nodes
  };

  Vocabulary() = default;
  /// Trains on descriptors grouped by image (the images give the IDF weights).
  /// `progress` (optional) is called with the share of the k-means work done, 0 to 1, as clustering goes on.
  static Vocabulary train(const std::vector<cv::Mat>& descriptors_per_image, const VocabularySettings& settings,
                          const std::function<void(double)>& progress = {});
  static constexpr int kMaxBranching = 64;
  static constexpr int kMaxDepth = 16;
  /// Builds from stored parts (used by the file reader). Throws std::invalid_argument saying what is wrong
  /// unless the parts form a tree: children stored after their parent, one parent per node, leaves
  /// carrying each word exactly once, no path deeper than `depth`, finite non-negative IDF weights.
  Vocabulary(int branching, int depth, std::vector<Node> nodes, std::vector<double> idf);

  int branching() const { return branching_; }
  int depth() const { return depth_; }
  int wordCount() const { return static_cast<int>(idf_.size()); }
  const std::vector<Node>& nodes() const { return nodes_; }
  const std::vector<double>& idf() const { return idf_; }
  bool empty() const { return nodes_.empty(); }

  /// The word a descriptor falls into (descending to the nearest child at every level).
  int wordOf(const std::uint8_t* descriptor) const;  ///< -1 for an empty vocabulary
  /// TF-IDF bag of words of an image's descriptors (CV_8U, 32 bytes per row), L1-normalised.
  BowVector transform(const cv::Mat& descriptors) const;

 private:
  void checkStructure() const;

  int branching_ = 0;
  int depth_ = 0;
  std::vector<Node> nodes_;  ///< nodes_[0] is the root
  std::vector<double> idf_;  ///< per word: log(N images / images containing the word)
};

/// DBoW2's L1 score of two L1-normalised vectors: 1 - |a - b|_1 / 2, in [0, 1] (1 = identical).
double bowScore(const BowVector& a, const BowVector& b);

/// Hamming distance of two 256-bit descriptors.
int hammingDistance(const std::uint8_t* a, const std::uint8_t* b);

}  // namespace groundslam
