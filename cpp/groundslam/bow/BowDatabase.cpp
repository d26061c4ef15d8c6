#include "groundslam/bow/BowDatabase.hpp"

#include <algorithm>
#include <cmath>

namespace groundslam {

void BowDatabase::add(int frame, const BowVector& bow) {
  for (const auto& [word, weight] : bow) inverted_[word].emplace_back(frame, weight);
  ++frames_;
}

std::vector<BowMatch> BowDatabase::query(const BowVector& bow, int max_results) const {
  // Accumulates DBoW2's L1 score only over shared words (see bowScore).
  std::unordered_map<int, double> shared;
  for (const auto& [word, weight] : bow) {
    const auto postings = inverted_.find(word);
    if (postings == inverted_.end()) continue;
    for (const auto& [frame, stored] : postings->second) {
      const double x = weight, y = stored;
      shared[frame] += std::abs(x - y) - std::abs(x) - std::abs(y);
    }
  }
  std::vector<BowMatch> matches;
  matches.reserve(shared.size());
  for (const auto& [frame, sum] : shared) matches.push_back({frame, std::clamp(-0.5 * sum, 0.0, 1.0)});
  const size_t keep = std::min(matches.size(), static_cast<size_t>(std::max(0, max_results)));
  std::partial_sort(matches.begin(), matches.begin() + static_cast<long>(keep), matches.end(),
                    [](const BowMatch& a, const BowMatch& b) { return a.score > b.score || (a.score == b.score && a.frame < b.frame); });
  matches.resize(keep);
  return matches;
}

}  // namespace groundslam
