// Does the cost of a frame stay flat as the map grows? Renders a long random walk in memory (rendering is
// not timed), runs the full pipeline, and prints the median frame time of the first and last 10% of frames
// and the memory kept per frame. Usage: scaling_benchmark [FRAMES=5000] [WIDTHxHEIGHT=320x240]
#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <ctime>
#include <unistd.h>

#include "groundslam/io/VocabularyFile.hpp"
#include "groundslam/pipeline/Slam.hpp"
#include "groundslam/sim/Simulator.hpp"

using namespace groundslam;

namespace {

double residentMegabytes() {
  std::ifstream statm("/proc/self/statm");
  long pages = 0, resident = 0;
  statm >> pages >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1e6;
}

/// CPU time of the whole process (all threads), milliseconds: unlike wall time, blind to other guests of
/// a virtual machine taking the cores for a while.
double processCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) / 1e6;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::atoi(argv[1]) : 5000;
  if (frames < 20) {
    std::fprintf(stderr, "scaling_benchmark: FRAMES must be at least 20 (got '%s')\n", argc > 1 ? argv[1] : "");
    return 2;
  }
  int width = 320, height = 240;
  if (argc > 2) std::sscanf(argv[2], "%dx%d", &width, &height);
  sim::SimulationSettings settings;
  settings.camera = sim::scaledHdGroundIntrinsics(width, height);
  settings.path.kind = sim::PathKind::random_walk;
  settings.path.frames = frames;
  settings.path.area_m = 1.5;  // a bounded area: the walk keeps revisiting, loops keep arriving
  settings.mount_jitter_deg = 0.3;
  const sim::SequenceSimulator simulator(settings);
  Config config;
  config.camera = cameraConfigOf(settings.camera, settings.mounting_height_m);
  Slam slam(config, std::make_shared<const Vocabulary>(readVocabulary(GROUNDSLAM_DEFAULT_VOCABULARY)));

  std::vector<double> ms, cpu_ms;
  std::vector<StageTimes> stages;
  const double rss_start = residentMegabytes();
  double rss_after_first_tenth = rss_start;
  int loops = 0;
  for (int i = 0; i < frames; ++i) {
    const cv::Mat image = simulator.renderFrame(i);
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = processCpuMs();
    const FrameResult r = slam.process(image, i);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    cpu_ms.push_back(processCpuMs() - cpu_start);
    loops += r.loop_closures;
    stages.push_back(r.times);
    if (i + 1 == frames / 10) rss_after_first_tenth = residentMegabytes();
    if ((i + 1) % 500 == 0) std::fprintf(stderr, "%d frames, %.1f MB resident\n", i + 1, residentMegabytes());
  }
  const double rss_end = residentMegabytes();
  const auto finish_start = std::chrono::steady_clock::now();
  slam.finish();
  const double finish_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - finish_start).count();
  const size_t tenth = static_cast<size_t>(frames / 10);
  const double first = median(std::vector<double>(ms.begin(), ms.begin() + static_cast<long>(tenth)));
  const double last = median(std::vector<double>(ms.end() - static_cast<long>(tenth), ms.end()));
  std::printf("frames: %d at %dx%d, loop closures: %d\n", frames, width, height, loops);
  std::printf("median frame time, first 10%%: %.2f ms, last 10%%: %.2f ms, ratio %.2f\n", first, last, last / first);
  const double cpu_first = median(std::vector<double>(cpu_ms.begin(), cpu_ms.begin() + static_cast<long>(tenth)));
  const double cpu_last = median(std::vector<double>(cpu_ms.end() - static_cast<long>(tenth), cpu_ms.end()));
  std::printf("median CPU time per frame, first 10%%: %.2f ms, last 10%%: %.2f ms, ratio %.2f\n", cpu_first, cpu_last,
              cpu_last / cpu_first);
  // Where the time goes: mean per stage (optimisation runs every few frames, so a median would hide it).
  const auto stage_means = [&](size_t from, size_t to) {
    StageTimes sum;
    for (size_t i = from; i < to; ++i) {
      sum.extract_ms += stages[i].extract_ms, sum.match_ms += stages[i].match_ms, sum.fit_ms += stages[i].fit_ms;
      sum.loop_ms += stages[i].loop_ms, sum.optimise_ms += stages[i].optimise_ms;
    }
    const double n = static_cast<double>(to - from);
    std::printf("extract %.2f, match %.2f, fit %.2f, loop %.2f, optimise %.2f", sum.extract_ms / n, sum.match_ms / n,
                sum.fit_ms / n, sum.loop_ms / n, sum.optimise_ms / n);
  };
  std::printf("mean stage times (ms), first 10%%: ");
  stage_means(0, tenth);
  std::printf("; last 10%%: ");
  stage_means(stages.size() - tenth, stages.size());
  std::printf("\n");
  // How much loop-closure verification each part of the run did, by outcome.
  const auto verified = [&](int from, int to) {
    int fitted = 0, matched_only = 0, cheap = 0;
    for (const LoopCandidate& c : slam.loopCandidates()) {
      if (c.frame_b < from || c.frame_b >= to) continue;
      if (!std::isnan(c.covariance_score)) ++fitted;
      else if (c.matches > 0) ++matched_only;
      else ++cheap;
    }
    const double n = to - from;
    std::printf("%.2f fitted, %.2f matched only, %.2f rejected before matching", fitted / n, matched_only / n, cheap / n);
  };
  std::printf("candidates per frame, first 10%%: ");
  verified(0, static_cast<int>(tenth));
  std::printf("; last 10%%: ");
  verified(frames - static_cast<int>(tenth), frames);
  std::printf("\n");
  const PlaceMap* places = slam.places();
  std::printf("places kept: %d of %d frames, %.1f MB of features; final whole-graph optimisation: %.0f ms\n",
              places ? places->size() : 0, frames, places ? static_cast<double>(places->bytes()) / 1e6 : 0.0, finish_ms);
  std::printf("resident memory: %.1f MB at start, %.1f MB at end; growth after the first 10%%: %.1f KB per frame\n",
              rss_start, rss_end, (rss_end - rss_after_first_tenth) * 1000.0 / (frames - static_cast<int>(tenth)));
  return 0;
}
