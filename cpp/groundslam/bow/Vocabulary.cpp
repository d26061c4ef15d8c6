#include "groundslam/bow/Vocabulary.hpp"

#include "groundslam/core/Hamming.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

namespace groundslam {
namespace {

Descriptor rowOf(const cv::Mat& descriptors, int row) {
  Descriptor d;
  std::memcpy(d.data(), descriptors.ptr<std::uint8_t>(row), d.size());
  return d;
}

/// Bitwise majority of a cluster: the point minimising the summed Hamming distance (the k-median).
Descriptor bitwiseMedian(const std::vector<const Descriptor*>& members) {
  std::array<int, 256> ones{};
  for (const Descriptor* d : members) {
    for (size_t bit = 0; bit < 256; ++bit) ones[bit] += ((*d)[bit / 8] >> (bit % 8)) & 1;
  }
  Descriptor median{};
  for (size_t bit = 0; bit < 256; ++bit) {
    if (2 * static_cast<size_t>(ones[bit]) > members.size()) median[bit / 8] = static_cast<std::uint8_t>(median[bit / 8] | (1u << (bit % 8)));
  }
  return median;
}

size_t nearestCentre(const Descriptor& d, const std::vector<Descriptor>& centres) {
  size_t best = 0;
  int best_distance = std::numeric_limits<int>::max();
  for (size_t c = 0; c < centres.size(); ++c) {
    const int distance = hammingDistance(d.data(), centres[c].data());
    if (distance < best_distance) best_distance = distance, best = c;
  }
  return best;
}

/// k-means++ seeding: each next centre drawn with probability proportional to squared distance.
std::vector<Descriptor> seedCentres(const std::vector<const Descriptor*>& points, int k, std::mt19937_64& rng) {
  std::vector<Descriptor> centres{*points[std::uniform_int_distribution<size_t>(0, points.size() - 1)(rng)]};
  std::vector<double> weight(points.size());
  while (static_cast<int>(centres.size()) < k) {
    for (size_t i = 0; i < points.size(); ++i) {
      const double d = hammingDistance(points[i]->data(), centres[nearestCentre(*points[i], centres)].data());
      weight[i] = d * d;
    }
    if (*std::max_element(weight.begin(), weight.end()) == 0.0) break;  // fewer distinct points than k
    centres.push_back(*points[std::discrete_distribution<size_t>(weight.begin(), weight.end())(rng)]);
  }
  return centres;
}

/// Splits points into up to k clusters by k-medians.
std::vector<std::vector<const Descriptor*>> cluster(const std::vector<const Descriptor*>& points, int k, int iterations,
                                                    std::mt19937_64& rng) {
  std::vector<Descriptor> centres = seedCentres(points, k, rng);
  std::vector<std::vector<const Descriptor*>> groups;
  for (int it = 0; it < iterations; ++it) {
    groups.assign(centres.size(), {});
    for (const Descriptor* p : points) groups[nearestCentre(*p, centres)].push_back(p);
    bool changed = false;
    for (size_t c = 0; c < centres.size(); ++c) {
      if (groups[c].empty()) continue;
      const Descriptor median = bitwiseMedian(groups[c]);
      changed = changed || median != centres[c];
      centres[c] = median;
    }
    if (!changed) break;
  }
  groups.erase(std::remove_if(groups.begin(), groups.end(), [](const auto& g) { return g.empty(); }), groups.end());
  return groups;
}

}  // namespace

int hammingDistance(const std::uint8_t* a, const std::uint8_t* b) { return hammingDistance256(a, b); }

Vocabulary::Vocabulary(int branching, int depth, std::vector<Node> nodes, std::vector<double> idf)
    : branching_(branching), depth_(depth), nodes_(std::move(nodes)), idf_(std::move(idf)) {
  checkStructure();
}

void Vocabulary::checkStructure() const {
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  if (branching_ < 2 || branching_ > kMaxBranching) fail("branching " + std::to_string(branching_) + " is not in [2, 64]");
  if (depth_ < 1 || depth_ > kMaxDepth) fail("depth " + std::to_string(depth_) + " is not in [1, 16]");
  if (nodes_.empty()) fail("the tree has no nodes");
  if (idf_.empty()) fail("the vocabulary has no words");
  const long long node_count = static_cast<long long>(nodes_.size());
  // Children are stored after their parent, so following children always moves forward: the tree is
  // acyclic and every descent ends at a leaf. Each node but the root has exactly one parent.
  std::vector<int> parents(nodes_.size(), 0), level(nodes_.size(), 0);
  std::vector<int> leaves_of_word(idf_.size(), 0);
  for (size_t i = 0; i < nodes_.size(); ++i) {
    const Node& n = nodes_[i];
    const std::string node = "node " + std::to_string(i) + ": ";
    if (n.child_count < 0 || n.child_count > branching_) fail(node + "child count " + std::to_string(n.child_count) + " is not in [0, branching]");
    if (n.child_count == 0) {
      if (n.word < 0 || n.word >= wordCount()) fail(node + "leaf word " + std::to_string(n.word) + " is out of range");
      ++leaves_of_word[static_cast<size_t>(n.word)];
      continue;
    }
    if (n.word != -1) fail(node + "an inner node carries word " + std::to_string(n.word));
    const long long first = n.first_child, end = first + n.child_count;
    if (first <= static_cast<long long>(i) || end > node_count) fail(node + "child index " + std::to_string(first) + " is out of range");
    for (long long c = first; c < end; ++c) {
      ++parents[static_cast<size_t>(c)];
      level[static_cast<size_t>(c)] = level[i] + 1;
      if (level[static_cast<size_t>(c)] > depth_) fail(node + "the tree is deeper than its depth " + std::to_string(depth_));
    }
  }
  for (size_t i = 1; i < nodes_.size(); ++i) {
    if (parents[i] != 1) fail("node " + std::to_string(i) + " has " + std::to_string(parents[i]) + " parents, not 1");
  }
  for (size_t w = 0; w < idf_.size(); ++w) {
    if (leaves_of_word[w] != 1) fail("word " + std::to_string(w) + " has " + std::to_string(leaves_of_word[w]) + " leaves, not 1");
    if (!std::isfinite(idf_[w]) || idf_[w] < 0.0) fail("word " + std::to_string(w) + " has IDF weight " + std::to_string(idf_[w]));
  }
}

Vocabulary Vocabulary::train(const std::vector<cv::Mat>& descriptors_per_image, const VocabularySettings& settings,
                             const std::function<void(double)>& progress) {
  std::vector<Descriptor> all;
  for (const cv::Mat& image : descriptors_per_image) {
    for (int r = 0; r < image.rows; ++r) all.push_back(rowOf(image, r));
  }
  Vocabulary vocabulary;
  vocabulary.branching_ = settings.branching;
  vocabulary.depth_ = settings.depth;
  if (all.empty()) return vocabulary;
  std::mt19937_64 rng(settings.seed);
  // Breadth-first construction: children of a node are stored consecutively.
  struct Pending {
    int node;
    int level;
    std::vector<const Descriptor*> points;
  };
  std::vector<const Descriptor*> everything;
  for (const Descriptor& d : all) everything.push_back(&d);
  vocabulary.nodes_.push_back(Node{bitwiseMedian(everything), -1, 0, -1});
  std::vector<Pending> queue{{0, 0, everything}};
  size_t clustered = 0;
  for (size_t q = 0; q < queue.size(); ++q) {
    Pending current = std::move(queue[q]);
    if (current.level >= settings.depth || static_cast<int>(current.points.size()) <= 1) {
      vocabulary.nodes_[static_cast<size_t>(current.node)].word = static_cast<int>(vocabulary.idf_.size());
      vocabulary.idf_.push_back(0.0);
      continue;
    }
    auto groups = cluster(current.points, settings.branching, settings.iterations, rng);
    // Each level clusters every descriptor once: the work done is the points clustered over depth x all.
    clustered += current.points.size();
    if (progress) progress(std::min(1.0, static_cast<double>(clustered) / (static_cast<double>(all.size()) * settings.depth)));
    Node& parent = vocabulary.nodes_[static_cast<size_t>(current.node)];
    parent.first_child = static_cast<int>(vocabulary.nodes_.size());
    parent.child_count = static_cast<int>(groups.size());
    for (auto& group : groups) {
      const int index = static_cast<int>(vocabulary.nodes_.size());
      vocabulary.nodes_.push_back(Node{bitwiseMedian(group), -1, 0, -1});
      queue.push_back({index, current.level + 1, std::move(group)});
    }
  }
  // IDF: log(N / n_i), n_i = training images in which word i occurs.
  std::vector<int> images_with_word(vocabulary.idf_.size(), 0);
  for (const cv::Mat& image : descriptors_per_image) {
    std::vector<bool> seen(vocabulary.idf_.size(), false);
    for (int r = 0; r < image.rows; ++r) seen[static_cast<size_t>(vocabulary.wordOf(image.ptr<std::uint8_t>(r)))] = true;
    for (size_t w = 0; w < seen.size(); ++w) images_with_word[w] += seen[w] ? 1 : 0;
  }
  const double n_images = static_cast<double>(descriptors_per_image.size());
  for (size_t w = 0; w < vocabulary.idf_.size(); ++w) {
    vocabulary.idf_[w] = std::log(n_images / std::max(1, images_with_word[w]));
  }
  return vocabulary;
}

int Vocabulary::wordOf(const std::uint8_t* descriptor) const {
  if (nodes_.empty()) return -1;
  size_t node = 0;
  while (nodes_[node].child_count > 0) {
    const Node& parent = nodes_[node];
    size_t best = static_cast<size_t>(parent.first_child);
    int best_distance = std::numeric_limits<int>::max();
    for (int c = 0; c < parent.child_count; ++c) {
      const size_t child = static_cast<size_t>(parent.first_child + c);
      const int distance = hammingDistance(descriptor, nodes_[child].centre.data());
      if (distance < best_distance) best_distance = distance, best = child;
    }
    node = best;
  }
  return nodes_[node].word;
}

BowVector Vocabulary::transform(const cv::Mat& descriptors) const {
  BowVector bow;
  if (nodes_.empty()) return bow;
  std::vector<int> words;
  words.reserve(static_cast<size_t>(descriptors.rows));
  for (int r = 0; r < descriptors.rows; ++r) words.push_back(wordOf(descriptors.ptr<std::uint8_t>(r)));
  std::sort(words.begin(), words.end());
  double total = 0.0;
  for (size_t i = 0; i < words.size();) {
    size_t end = i;
    while (end < words.size() && words[end] == words[i]) ++end;
    // Term frequency times IDF.
    const double weight = static_cast<double>(end - i) * idf_[static_cast<size_t>(words[i])];
    bow.emplace_back(words[i], static_cast<float>(weight));
    total += weight;
    i = end;
  }
  if (total > 0.0) {
    for (auto& entry : bow) entry.second = static_cast<float>(entry.second / total);
  }
  return bow;
}

double bowScore(const BowVector& a, const BowVector& b) {
  // For L1-normalised vectors: |a - b|_1 = 2 + sum over shared words of (|a_i - b_i| - |a_i| - |b_i|).
  double shared = 0.0;
  auto i = a.begin();
  auto j = b.begin();
  while (i != a.end() && j != b.end()) {
    if (i->first < j->first) {
      ++i;
    } else if (j->first < i->first) {
      ++j;
    } else {
      const double x = i->second, y = j->second;
      shared += std::abs(x - y) - std::abs(x) - std::abs(y);
      ++i, ++j;
    }
  }
  return std::clamp(-0.5 * shared, 0.0, 1.0);
}

}  // namespace groundslam
