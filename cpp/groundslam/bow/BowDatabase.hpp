#pragma once
// The image database of paper §III-C1: bag-of-words vectors of earlier frames in an inverted index,
// queried for the frames most similar to the current one.

#include <unordered_map>
#include <utility>
#include <vector>

#include "groundslam/bow/Vocabulary.hpp"

namespace groundslam {

struct BowMatch {
  int frame = 0;       ///< the frame id given to add()
  double score = 0.0;  ///< bowScore in [0, 1]
};

class BowDatabase {
 public:
  void add(int frame, const BowVector& bow);
  /// The best `max_results` frames by score, best first. Cost grows with the postings of the
  /// query's words, not with the frames that share none of them. It reuses scratch arrays of the
  /// database: one query at a time per database.
  std::vector<BowMatch> query(const BowVector& bow, int max_results) const;
  int size() const { return static_cast<int>(frames_.size()); }

 private:
  std::unordered_map<int, std::vector<std::pair<int, float>>> inverted_;  ///< word -> (entry, weight)
  std::vector<int> frames_;  ///< entry -> frame id; entries are dense, so scores accumulate in an array
  mutable std::vector<double> sums_;   ///< per entry, all zero between queries
  mutable std::vector<int> touched_;   ///< entries with a non-zero sum during a query
};

}  // namespace groundslam
