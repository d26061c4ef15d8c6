#include "groundslam/io/ConfigNames.hpp"

namespace groundslam {

const NameTable<RobustLoss>& namesOf(RobustLoss) {
  static const NameTable<RobustLoss> names = {
      {RobustLoss::huber, "huber"}, {RobustLoss::cauchy, "cauchy"}, {RobustLoss::geman_mcclure, "geman_mcclure"}};
  return names;
}

const NameTable<MatcherMethod>& namesOf(MatcherMethod) {
  static const NameTable<MatcherMethod> names = {{MatcherMethod::brute_force, "brute_force"}, {MatcherMethod::lsh, "lsh"}};
  return names;
}

const NameTable<OrbScore>& namesOf(OrbScore) {
  static const NameTable<OrbScore> names = {{OrbScore::harris, "harris"}, {OrbScore::fast, "fast"}};
  return names;
}

const NameTable<DistortionModel>& namesOf(DistortionModel) {
  static const NameTable<DistortionModel> names = {{DistortionModel::radtan, "radtan"},
                                                   {DistortionModel::equidistant, "equidistant"}};
  return names;
}

}  // namespace groundslam
