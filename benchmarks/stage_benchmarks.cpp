// Per-stage costs on simulated 1600x1200 frames (HD Ground's camera). Run: build/benchmarks/stage_benchmarks
#include <benchmark/benchmark.h>

#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/Matching.hpp"
#include "groundslam/core/RigidFit.hpp"
#include "groundslam/sim/Simulator.hpp"

using namespace groundslam;

namespace {

/// Two consecutive HD frames of simulated asphalt, rendered once.
struct HdFrames {
  sim::SimulationSettings settings;
  cv::Mat first, second;
  CameraModel camera{CameraIntrinsics{}, Eigen::Isometry3d::Identity()};

  HdFrames() {
    settings.camera = sim::scaledHdGroundIntrinsics(1600, 1200);
    settings.path.frames = 2;
    const sim::SequenceSimulator simulator(settings);
    first = simulator.renderFrame(0);
    second = simulator.renderFrame(1);
    camera = simulator.camera();
  }
};

const HdFrames& frames() {
  static const HdFrames instance;
  return instance;
}

GroundFeatures groundFeatures(const cv::Mat& image) {
  return projectToGround(OrbExtractor(OrbSettings{}).detect(image), frames().camera);
}

void BM_OrbExtraction(benchmark::State& state) {
  const OrbExtractor extractor{OrbSettings{}};
  for (auto _ : state) benchmark::DoNotOptimize(extractor.detect(frames().first));
}
BENCHMARK(BM_OrbExtraction)->Unit(benchmark::kMillisecond);

void BM_GroundProjection(benchmark::State& state) {
  const ImageFeatures features = OrbExtractor(OrbSettings{}).detect(frames().first);
  for (auto _ : state) benchmark::DoNotOptimize(projectToGround(features, frames().camera));
}
BENCHMARK(BM_GroundProjection)->Unit(benchmark::kMillisecond);

void matchWith(benchmark::State& state, const std::string& method) {
  const GroundFeatures a = groundFeatures(frames().first), b = groundFeatures(frames().second);
  const DescriptorMatcher matcher({0.7, method});
  size_t matches = 0;
  for (auto _ : state) matches = matcher.match(b.descriptors, a.descriptors).size();
  state.counters["matches"] = static_cast<double>(matches);
}
void BM_MatchBruteForce(benchmark::State& state) { matchWith(state, "brute_force"); }
void BM_MatchLsh(benchmark::State& state) { matchWith(state, "lsh"); }
BENCHMARK(BM_MatchBruteForce)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MatchLsh)->Unit(benchmark::kMillisecond);

void BM_RobustFit(benchmark::State& state) {
  const GroundFeatures a = groundFeatures(frames().first), b = groundFeatures(frames().second);
  const auto matches = DescriptorMatcher({0.7, "brute_force"}).match(b.descriptors, a.descriptors);
  std::vector<Eigen::Vector2d> target, source;
  for (const auto& m : matches) {
    target.push_back(a.points[static_cast<size_t>(m.train)]);
    source.push_back(b.points[static_cast<size_t>(m.query)]);
  }
  for (auto _ : state) benchmark::DoNotOptimize(fitRigidTransform(target, source, FitSettings{}));
  state.counters["matches"] = static_cast<double>(matches.size());
}
BENCHMARK(BM_RobustFit)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
