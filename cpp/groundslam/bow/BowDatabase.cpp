#include "groundslam/bow/BowDatabase.hpp"

#include <algorithm>
#include <cmath>

namespace groundslam {

void BowDatabase::add(int frame, const BowVector& bow) {
  const int entry = static_cast<int>(frames_.size());
  for (const auto& [word, weight] : bow) inverted_[word].emplace_back(entry, weight);
  frames_.push_back(frame);
  sums_.push_back(0.0);
}

std::vector<BowMatch> BowDatabase::query(const BowVector& bow, int max_results) const {
  // Accumulates DBoW2's L1 score only over shared words (see bowScore), in an array indexed by entry.
  for (const auto& [word, weight] : bow) {
    const auto postings = inverted_.find(word);
    if (postings == inverted_.end()) continue;
    for (const auto& [entry, stored] : postings->second) {
      const double x = weight, y = stored;
      double& sum = sums_[static_cast<size_t>(entry)];
      if (sum == 0.0) touched_.push_back(entry);
      sum += std::abs(x - y) - std::abs(x) - std::abs(y);
      if (sum == 0.0) sum = -1e-300;  // stays marked as touched
    }
  }
  std::vector<BowMatch> matches;
  matches.reserve(touched_.size());
  for (const int entry : touched_) {
    double& sum = sums_[static_cast<size_t>(entry)];
    matches.push_back({frames_[static_cast<size_t>(entry)], std::clamp(-0.5 * sum, 0.0, 1.0)});
    sum = 0.0;
  }
  touched_.clear();
  const size_t keep = std::min(matches.size(), static_cast<size_t>(std::max(0, max_results)));
  std::partial_sort(matches.begin(), matches.begin() + static_cast<long>(keep), matches.end(),
                    [](const BowMatch& a, const BowMatch& b) { return a.score > b.score || (a.score == b.score && a.frame < b.frame); });
  matches.resize(keep);
  return matches;
}

}  // namespace groundslam
