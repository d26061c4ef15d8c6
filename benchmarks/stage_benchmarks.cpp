// Per-stage costs on simulated 1600x1200 frames (HD Ground's camera). Run: build/benchmarks/stage_benchmarks
#include <algorithm>
#include <cmath>
#include <random>

#include <map>
#include <utility>

#include <benchmark/benchmark.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "groundslam/core/FeatureExtraction.hpp"
#include "groundslam/core/ImageAlignment.hpp"
#include "groundslam/core/Matching.hpp"
#include "groundslam/core/MotionPrior.hpp"
#include "groundslam/core/MotionSearch.hpp"
#include "groundslam/core/NearestDescriptors.hpp"
#include "groundslam/core/PointTracking.hpp"
#include "groundslam/core/MountEstimation.hpp"
#include "groundslam/core/MountSmoother.hpp"
#include "groundslam/core/StillFeatures.hpp"
#include "groundslam/core/PoseGraph.hpp"
#include "groundslam/core/RigidFit.hpp"
#include "groundslam/core/ImageReduction.hpp"
#include "groundslam/core/Repetition.hpp"
#include "groundslam/core/SpectralTurn.hpp"
#include "groundslam/bow/BowDatabase.hpp"
#include "groundslam/io/VocabularyFile.hpp"
#include "groundslam/pipeline/FramePreparer.hpp"
#include "groundslam/sim/Simulator.hpp"

using namespace groundslam;

namespace {

/// Two consecutive HD frames of simulated asphalt, rendered once.
struct HdFrames {
  sim::SimulationSettings settings;
  cv::Mat first, second;
  CameraModel camera{CameraIntrinsics{}, Eigen::Isometry3d::Identity()};
  Pose2 simulator_truth_a_b;

  HdFrames() {
    settings.camera = sim::scaledHdGroundIntrinsics(1600, 1200);
    settings.path.frames = 2;
    const sim::SequenceSimulator simulator(settings);
    first = simulator.renderFrame(0);
    second = simulator.renderFrame(1);
    camera = simulator.camera();
    simulator_truth_a_b = between(simulator.groundTruth()[0], simulator.groundTruth()[1]);
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
  const cv::Mat& image = frames().first;  // rendered once, before timing
  for (auto _ : state) benchmark::DoNotOptimize(extractor.detect(image));
}
BENCHMARK(BM_OrbExtraction)->Unit(benchmark::kMillisecond);

// Realistic HD images (issue #14): sensor noise 2, 4 or 8 grey levels, motion blur, vignetting and mount
// rocking, on procedural asphalt (texture 0) or on a photo of gravel (texture 1, from Debian's python3-skimage).
constexpr const char* kPhotoTexture = "/usr/lib/python3/dist-packages/skimage/data/gravel.png";

const cv::Mat& realisticFrame(int texture, int noise) {
  static std::map<std::pair<int, int>, cv::Mat> rendered;
  cv::Mat& frame = rendered[{texture, noise}];
  if (!frame.empty()) return frame;
  sim::SimulationSettings settings;
  settings.camera = sim::scaledHdGroundIntrinsics(1600, 1200);
  settings.path.frames = 2;
  settings.seed = 21;
  settings.motion_blur = 0.3;
  settings.mount_jitter_deg = 0.3;
  settings.photometry.vignetting = 0.3;
  settings.photometry.noise_sigma = noise;
  cv::Mat photo;
  if (texture == 1) {
    photo = cv::imread(kPhotoTexture, cv::IMREAD_GRAYSCALE);
    if (photo.empty()) return frame;  // python3-skimage not installed: the benchmark reports it
    settings.user_texture_width_m = 0.6;
    settings.path.step_m = 0.004;
  }
  frame = sim::SequenceSimulator(settings, photo).renderFrame(1);
  return frame;
}

/// Arguments: texture (0 asphalt, 1 gravel photo), noise, extractor (0: OpenCV's default ORB, full resolution;
/// 1: groundslam's settings at full resolution; 2: groundslam's defaults, reduced to 800 pixels wide).
void BM_OrbRealistic(benchmark::State& state) {
  const cv::Mat& image = realisticFrame(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  if (image.empty()) {
    state.SkipWithError("photo texture missing: apt-get install python3-skimage");
    return;
  }
  const int extractor = static_cast<int>(state.range(2));
  OrbSettings settings;
  if (extractor == 1) settings.max_extraction_width = 0;
  const OrbExtractor ours(settings);
  const cv::Ptr<cv::ORB> reference = cv::ORB::create();
  size_t keypoints = 0;
  for (auto _ : state) {
    if (extractor == 0) {
      std::vector<cv::KeyPoint> found;
      cv::Mat descriptors;
      reference->detectAndCompute(image, cv::noArray(), found, descriptors);
      keypoints = found.size();
    } else {
      keypoints = ours.detect(image).keypoints.size();
    }
  }
  state.counters["keypoints"] = static_cast<double>(keypoints);
}
BENCHMARK(BM_OrbRealistic)->ArgsProduct({{0, 1}, {2, 4, 8}, {0, 1, 2}})->Unit(benchmark::kMillisecond);

/// ORB on a 320x240 frame (the texture matrix's size, noise 2): 0 groundslam's defaults; 1 FAST threshold 10;
/// 2 three pyramid levels; 3 FAST scores instead of Harris; 4 no glare check; 5 OpenCV's default ORB.
void BM_OrbSmall(benchmark::State& state) {
  static const cv::Mat image = [] {
    sim::SimulationSettings settings;
    settings.path.frames = 2;
    settings.mount_jitter_deg = 0.3;
    return sim::SequenceSimulator(settings).renderFrame(1);
  }();
  OrbSettings settings;
  const int variant = static_cast<int>(state.range(0));
  if (variant == 1) settings.fast_threshold = 10;
  if (variant == 2) settings.num_levels = 3;
  if (variant == 3) settings.score_type = OrbScore::fast;
  if (variant == 4) settings.flatten_window = 0.0;
  if (variant == 5) {
    settings = OrbSettings{1000, 1.2, 8, 20, 31, 31, OrbScore::harris, 0, 0, 0.0};
  }
  const OrbExtractor extractor(settings);
  size_t keypoints = 0;
  for (auto _ : state) keypoints = extractor.detect(image).keypoints.size();
  state.counters["keypoints"] = static_cast<double>(keypoints);
}
BENCHMARK(BM_OrbSmall)->DenseRange(0, 5)->Unit(benchmark::kMillisecond);

/// Decoding one realistic HD frame (asphalt, noise 4) from memory. Arguments: 0 PNG, 1 JPEG (quality 95),
/// 2 JPEG decoded at half size (cv::IMREAD_REDUCED_GRAYSCALE_2, what the frame preparers use for HD JPEG).
void BM_Decode(benchmark::State& state) {
  const cv::Mat& image = realisticFrame(0, 4);
  const int variant = static_cast<int>(state.range(0));
  std::vector<std::uint8_t> bytes;
  cv::imencode(variant == 0 ? ".png" : ".jpg", image, bytes, {cv::IMWRITE_JPEG_QUALITY, 95});
  const int flag = variant == 2 ? cv::IMREAD_REDUCED_GRAYSCALE_2 : cv::IMREAD_GRAYSCALE;
  int width = 0;
  for (auto _ : state) width = cv::imdecode(bytes, flag).cols;
  state.counters["kB"] = static_cast<double>(bytes.size()) / 1024.0;
  state.counters["width"] = width;
}
BENCHMARK(BM_Decode)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

void BM_GroundProjection(benchmark::State& state) {
  const ImageFeatures features = OrbExtractor(OrbSettings{}).detect(frames().first);
  for (auto _ : state) benchmark::DoNotOptimize(projectToGround(features, frames().camera));
}
BENCHMARK(BM_GroundProjection)->Unit(benchmark::kMillisecond);

void matchWith(benchmark::State& state, MatcherMethod method) {
  const GroundFeatures a = groundFeatures(frames().first), b = groundFeatures(frames().second);
  const DescriptorMatcher matcher({0.7, method});
  size_t matches = 0;
  for (auto _ : state) matches = matcher.match(b.descriptors, a.descriptors).size();
  state.counters["matches"] = static_cast<double>(matches);
}
void BM_MatchBruteForce(benchmark::State& state) { matchWith(state, MatcherMethod::brute_force); }
void BM_MatchLsh(benchmark::State& state) { matchWith(state, MatcherMethod::lsh); }
BENCHMARK(BM_MatchBruteForce)->Unit(benchmark::kMillisecond);

/// The two nearest of 1500 x 1500 descriptors per kernel: 1 scalar (POPCNT), 2 AVX2, 3 AVX-512 VPOPCNTDQ.
void BM_TwoNearest(benchmark::State& state) {
  const auto kernel = static_cast<HammingKernel>(state.range(0));
  const auto kernels = supportedHammingKernels();
  if (std::find(kernels.begin(), kernels.end(), kernel) == kernels.end()) {
    state.SkipWithError("this CPU lacks the kernel");
    return;
  }
  const GroundFeatures a = groundFeatures(frames().first), b = groundFeatures(frames().second);
  for (auto _ : state) benchmark::DoNotOptimize(twoNearest(b.descriptors, a.descriptors, kernel));
}
BENCHMARK(BM_TwoNearest)->DenseRange(1, 3)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MatchLsh)->Unit(benchmark::kMillisecond);

void BM_RobustFit(benchmark::State& state) {
  const GroundFeatures a = groundFeatures(frames().first), b = groundFeatures(frames().second);
  const auto matches = DescriptorMatcher({0.7, MatcherMethod::brute_force}).match(b.descriptors, a.descriptors);
  std::vector<Eigen::Vector2d> target, source;
  for (const auto& m : matches) {
    target.push_back(a.points[static_cast<size_t>(m.train)]);
    source.push_back(b.points[static_cast<size_t>(m.query)]);
  }
  // Arg 1: as odometry fits, every RANSAC hypothesis tried to measure the rivals and list the repetitions.
  FitSettings settings;
  settings.measure_ambiguity = state.range(0) == 1;
  settings.rival_max_rotation_rad = 1.0 * M_PI / 180.0;
  for (auto _ : state) benchmark::DoNotOptimize(fitRigidTransform(target, source, settings));
  state.counters["matches"] = static_cast<double>(matches.size());
}
BENCHMARK(BM_RobustFit)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_MotionPriorChoice(benchmark::State& state) {
  // A refused fit on a repeated floor: the fit and three repetitions, judged against eight steps' predictions.
  const Pose2 step(0.0, -0.01, 1.75 * M_PI / 180.0);
  const MotionPrior prior(step, 1, 8, MotionPriorSettings{});
  Pose2 truth;
  for (int k = 0; k < 6; ++k) truth = truth * step;
  const std::vector<Pose2> candidates{Pose2(truth.x + 0.04, truth.y, truth.theta), Pose2(truth.x - 0.04, truth.y, truth.theta),
                                      Pose2(truth.x, truth.y - 0.04, truth.theta), truth};
  for (auto _ : state) benchmark::DoNotOptimize(prior.choose(candidates));
}
BENCHMARK(BM_MotionPriorChoice)->Unit(benchmark::kMicrosecond);

void BM_MotionPriorSupportChoice(benchmark::State& state) {
  // Driving straight: one step and the repetition a tile on (five steps) both fit the steps; the matches decide.
  // Two usual steps, as right after a turn on the spot.
  const Pose2 step(0.01, 0.0, 0.0);
  const MotionPrior prior(std::vector<Pose2>{step, Pose2(0.0, -0.01, 0.0)}, 1, 8, MotionPriorSettings{});
  const std::vector<Pose2> candidates{Pose2(0.0098, -0.003, 0.0), Pose2(0.0482, -0.0034, 0.0), Pose2(0.0086, 0.036, 0.0)};
  const std::vector<int> support{63, 13, 28};
  for (auto _ : state) benchmark::DoNotOptimize(prior.choose(candidates, support));
}
BENCHMARK(BM_MotionPriorSupportChoice)->Unit(benchmark::kMicrosecond);

void BM_LoopVerificationMatching(benchmark::State& state) {
  // A loop candidate's guided matching within the default drift window with no drift path:
  // 0.015 m + 0.15 m * 0.035 rad + 5 mm of keypoint slack.
  const GroundFeatures a = groundFeatures(frames().first), b = groundFeatures(frames().second);
  const Pose2 estimate = frames().simulator_truth_a_b;
  for (auto _ : state) benchmark::DoNotOptimize(matchNearby(b, a, estimate, 0.025, 0.7));
  state.counters["matches"] = static_cast<double>(matchNearby(b, a, estimate, 0.025, 0.7).size());
}
BENCHMARK(BM_LoopVerificationMatching)->Unit(benchmark::kMillisecond);

void BM_MotionSearch(benchmark::State& state) {
  // A bridging frame's search (odometry.bridge_search_*): per usual step, 8 step counts and 72 turns on the spot,
  // each guiding the matching within 8 mm (two usual steps right after a turn: 160 hypotheses).
  const GroundFeatures a = groundFeatures(frames().first), b = groundFeatures(frames().second);
  const Pose2 step = frames().simulator_truth_a_b;
  std::vector<Pose2> hypotheses;
  for (int usual = 0; usual < 2; ++usual) {
    Pose2 steps;
    for (int k = 1; k <= 8; ++k) hypotheses.push_back(steps = steps * step);
    for (const Pose2& turn : turnHypotheses(step, 5.0 * M_PI / 180.0)) hypotheses.push_back(turn);
  }
  const FitSettings fitting;
  for (auto _ : state) benchmark::DoNotOptimize(searchMotion(b, a, hypotheses, MotionSearchSettings{}, fitting));
  const auto found = searchMotion(b, a, hypotheses, MotionSearchSettings{}, fitting);
  state.counters["inliers"] = found ? static_cast<double>(found->fit.inliers) : 0.0;
}
BENCHMARK(BM_MotionSearch)->Unit(benchmark::kMillisecond);

void BM_IlluminationFlattening(benchmark::State& state) {
  // state.range(0) = 1: an image with a glare patch (flattened); 0: even light (only the check runs).
  cv::Mat image = frames().first.clone();
  if (state.range(0) == 1) {
    // The simulator's glare at HD: +160 grey levels at the centre, sigma 10% of the width.
    cv::Mat glare(image.size(), CV_8U);
    for (int row = 0; row < image.rows; ++row) {
      for (int col = 0; col < image.cols; ++col) {
        const double r2 = (std::pow(col - 800.0, 2) + std::pow(row - 600.0, 2)) / (160.0 * 160.0);
        glare.at<std::uint8_t>(row, col) = cv::saturate_cast<std::uint8_t>(160.0 * std::exp(-0.5 * r2));
      }
    }
    cv::add(image, glare, image);
  }
  const double sigma = OrbSettings{}.flatten_window * image.cols;
  for (auto _ : state) benchmark::DoNotOptimize(flattenIllumination(image, sigma, OrbSettings{}.flatten_min_range));
}
BENCHMARK(BM_IlluminationFlattening)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_StillSplit(benchmark::State& state) {
  const GroundFeatures a = groundFeatures(frames().first), b = groundFeatures(frames().second);
  const auto matches = DescriptorMatcher({0.7, MatcherMethod::brute_force}).match(b.descriptors, a.descriptors);
  for (auto _ : state) benchmark::DoNotOptimize(splitStillMatches(matches, b, a, 1.5 / frames().camera.intrinsics().fx));
  state.counters["matches"] = static_cast<double>(matches.size());
}
BENCHMARK(BM_StillSplit)->Unit(benchmark::kMillisecond);

void BM_StillFeatures(benchmark::State& state) {
  // Every feature of one frame looked up at its own image place in the previous frame (no matching).
  const GroundFeatures a = groundFeatures(frames().first), b = groundFeatures(frames().second);
  std::size_t found = 0;
  for (auto _ : state) {
    const auto still = findStillFeatures(b, a, 1.5 / frames().camera.intrinsics().fx, 40);
    found = still.size();
    benchmark::DoNotOptimize(still);
  }
  state.counters["features"] = static_cast<double>(b.size());
  state.counters["still"] = static_cast<double>(found);
}
BENCHMARK(BM_StillFeatures)->Unit(benchmark::kMillisecond);

void BM_AlignmentImage(benchmark::State& state) {
  // Paid by every frame while odometry.align_images is on: the HD image reduced to 160 pixels wide, high-passed.
  const ImageAlignmentSettings settings;
  const cv::Mat& image = frames().first;  // rendered before the timing
  for (auto _ : state) benchmark::DoNotOptimize(alignmentImage(image, settings));
}
BENCHMARK(BM_AlignmentImage)->Unit(benchmark::kMillisecond);

/// The simulator's true motion between the two frames as a warp of current pixels to previous ones, through the
/// camera, 2 pixels off: where an alignment starts from.
cv::Matx23d trueWarpTwoPixelsOff() {
  std::vector<cv::Point2f> current_pixels{{400, 300}, {1200, 300}, {400, 900}}, previous_pixels;
  for (const cv::Point2f& p : current_pixels) {
    const auto ground = frames().camera.pixelToGround(Eigen::Vector2d(p.x, p.y));
    const auto seen = frames().camera.groundToPixel(frames().simulator_truth_a_b * *ground);
    previous_pixels.emplace_back(static_cast<float>(seen->x() + 2.0), static_cast<float>(seen->y()));
  }
  return cv::Matx23d(cv::getAffineTransform(current_pixels, previous_pixels));
}

void BM_ImageAlignment(benchmark::State& state) {
  // Paid only by a frame whose features fail: the still parts, one start at the simulator's true motion moved by
  // 2 pixels, and the four probes around the solution.
  const ImageAlignmentSettings settings;
  const AlignmentImage a = alignmentImage(frames().first, settings), b = alignmentImage(frames().second, settings);
  const cv::Matx23d start = trueWarpTwoPixelsOff();
  double correlation = 0.0;
  for (auto _ : state) {
    const ImageAlignment aligned = alignImages(a, b, {start}, settings);
    correlation = aligned.correlation;
    benchmark::DoNotOptimize(aligned);
  }
  state.counters["correlation"] = correlation;
}
BENCHMARK(BM_ImageAlignment)->Unit(benchmark::kMillisecond);

/// One heading refinement on images of `settings`: the still parts and one ECC run from the fit's motion (here the
/// simulator's true motion moved by 2 pixels), no probes.
void refineHeading(benchmark::State& state, const ImageAlignmentSettings& settings) {
  const AlignmentImage a = alignmentImage(frames().first, settings), b = alignmentImage(frames().second, settings);
  const cv::Matx23d start = trueWarpTwoPixelsOff();
  double correlation = 0.0;
  for (auto _ : state) {
    const ImageAlignment refined = refineAlignment(a, b, start, settings);
    correlation = refined.correlation;
    benchmark::DoNotOptimize(refined);
  }
  state.counters["correlation"] = correlation;
}

void BM_HeadingRefinement(benchmark::State& state) {
  // Paid by every measured frame where nothing stays still in the image (odometry.align_heading_sigma_deg).
  refineHeading(state, ImageAlignmentSettings());
}
BENCHMARK(BM_HeadingRefinement)->Unit(benchmark::kMillisecond);

void BM_HeadingImage(benchmark::State& state) {
  // Paid by every frame while headings are refined (outdoor.heading_image_width_px): the HD image reduced to 320
  // wide, its background light removed, its contrast normalised, the light's edges found.
  const ImageAlignmentSettings settings = headingImageSettingsFrom(Config());
  for (auto _ : state) benchmark::DoNotOptimize(alignmentImage(frames().first, settings));
}
BENCHMARK(BM_HeadingImage)->Unit(benchmark::kMillisecond);

void BM_HeadingRefinementOnHeadingImages(benchmark::State& state) {
  // Paid by every measured frame where something stays still in the image: one ECC run on the contrast-normalised
  // images (320 wide) from the fit's motion, the still parts and the light's edges left out (here clean frames:
  // little is left out).
  refineHeading(state, headingImageSettingsFrom(Config()));
}
BENCHMARK(BM_HeadingRefinementOnHeadingImages)->Unit(benchmark::kMillisecond);

void BM_TurnImage(benchmark::State& state) {
  // Paid by every frame while odometry.fallback_turn_image_width_px is on: the HD image reduced to 320 wide.
  for (auto _ : state) benchmark::DoNotOptimize(reduceByWholeFactor(frames().first, Config().fallback.turn_image_width_px));
}
BENCHMARK(BM_TurnImage)->Unit(benchmark::kMillisecond);

void BM_SpectralTurn(benchmark::State& state) {
  // Paid only by a frame whose motion failed with no turn measured: the two polar spectra and their correlation,
  // then the phase correlation of each of the two turns half a turn apart (320 x 240 images).
  const int width = Config().fallback.turn_image_width_px;
  const cv::Mat a = reduceByWholeFactor(frames().first, width).pixels, b = reduceByWholeFactor(frames().second, width).pixels;
  double ratio = 0.0;
  for (auto _ : state) {
    const SpectralTurn found = spectralTurn(a, b);
    benchmark::DoNotOptimize(phasePeakAfterTurn(a, b, found.turn_rad));
    benchmark::DoNotOptimize(phasePeakAfterTurn(a, b, found.turn_rad + M_PI));
    ratio = found.peak_ratio;
  }
  state.counters["peak_ratio"] = ratio;
}
BENCHMARK(BM_SpectralTurn)->Unit(benchmark::kMillisecond);

void BM_RepetitionStrength(benchmark::State& state) {
  // Paid every odometry.floor_repeat_check_frames frames until the floor is found to repeat: the autocorrelation of
  // the 320-wide image's central square and its second peaks.
  const cv::Mat image = reduceByWholeFactor(frames().first, Config().fallback.turn_image_width_px).pixels;
  double strength = 0.0;
  for (auto _ : state) strength = repetitionStrength(image);
  state.counters["strength"] = strength;
}
BENCHMARK(BM_RepetitionStrength)->Unit(benchmark::kMillisecond);

void BM_TrackingImage(benchmark::State& state) {
  // Paid by every frame while the mount is estimated (outdoor.track_points): the HD image reduced to 320 wide, its
  // background light removed, its contrast normalised over the tracker's window.
  const PointTrackingSettings settings;
  for (auto _ : state) benchmark::DoNotOptimize(trackingImage(frames().first, settings));
}
BENCHMARK(BM_TrackingImage)->Unit(benchmark::kMillisecond);

void BM_PointTracking(benchmark::State& state) {
  // Paid by every frame whose mount is estimated from tracked points: 300 points (the mount estimate's pairs) tracked
  // from the simulator's true motion moved by 2 pixels: the warp, the still parts, Lucas-Kanade both ways, the plane's
  // RANSAC.
  const PointTrackingSettings settings;
  const TrackingImage a = trackingImage(frames().first, settings), b = trackingImage(frames().second, settings);
  const cv::Matx23d W = trueWarpTwoPixelsOff();
  const cv::Matx33d start(W(0, 0), W(0, 1), W(0, 2), W(1, 0), W(1, 1), W(1, 2), 0.0, 0.0, 1.0);
  std::vector<cv::Point2d> points;
  for (int row = 0; row < 15; ++row) {
    for (int col = 0; col < 20; ++col) points.emplace_back(200.0 + 60.0 * col, 180.0 + 60.0 * row);
  }
  size_t tracked = 0;
  for (auto _ : state) {
    const auto result = trackPoints(a, b, points, start, settings);
    tracked = static_cast<size_t>(std::count_if(result.begin(), result.end(), [](const auto& p) { return p.has_value(); }));
    benchmark::DoNotOptimize(result);
  }
  state.counters["tracked"] = static_cast<double>(tracked);
}
BENCHMARK(BM_PointTracking)->Unit(benchmark::kMillisecond);

void BM_MountEstimation(benchmark::State& state) {
  // One reference (the previous frame), the default 300 pairs; the pipeline uses up to three.
  const GroundFeatures a = groundFeatures(frames().first), b = groundFeatures(frames().second);
  const auto matches = DescriptorMatcher({0.7, MatcherMethod::brute_force}).match(b.descriptors, a.descriptors);
  std::vector<Eigen::Vector2d> reference, current;
  for (const auto& m : matches) {
    reference.push_back(a.rays[static_cast<size_t>(m.train)]);
    current.push_back(b.rays[static_cast<size_t>(m.query)]);
  }
  const Eigen::Isometry3d mount = frames().camera.T_robot_camera();
  MountEstimationSettings settings;
  settings.point_sigma_m = 0.35 * frames().camera.groundSampleDistance();
  for (auto _ : state) {
    benchmark::DoNotOptimize(estimateMount(reference, current, mount, calibratedState(mount), frames().simulator_truth_a_b, settings));
  }
  state.counters["pairs"] = static_cast<double>(std::min<size_t>(reference.size(), 300));
}
BENCHMARK(BM_MountEstimation)->Unit(benchmark::kMillisecond);

void BM_StepRemeasure(benchmark::State& state) {
  // What finish() pays per odometry step with outdoor.remeasure_odometry: the step's 64 kept pairs projected through
  // the two frames' mounts as used and as solved over the run, and fitted each time from the step.
  const GroundFeatures a = groundFeatures(frames().first), b = groundFeatures(frames().second);
  const auto matches = DescriptorMatcher({0.7, MatcherMethod::brute_force}).match(b.descriptors, a.descriptors);
  GroundFeatures pa, pb;
  const size_t count = std::min<size_t>(64, matches.size());
  for (size_t k = 0; k < count; ++k) {
    const Match& m = matches[k * matches.size() / count];
    pa.rays.push_back(a.rays[static_cast<size_t>(m.train)]);
    pb.rays.push_back(b.rays[static_cast<size_t>(m.query)]);
  }
  pa.points.assign(count, Eigen::Vector2d::Zero());
  pb.points.assign(count, Eigen::Vector2d::Zero());
  const Eigen::Isometry3d calibrated = frames().camera.T_robot_camera();
  MountState solved = calibratedState(calibrated);
  solved.roll_rad += 0.003;
  solved.pitch_rad -= 0.002;
  const FitSettings settings;
  for (auto _ : state) {
    for (const Eigen::Isometry3d& mount : {calibrated, mountFor(calibrated, solved)}) {
      reprojectToGround(pa, mount);
      reprojectToGround(pb, mount);
      benchmark::DoNotOptimize(refineRigidTransform(pa.points, pb.points, frames().simulator_truth_a_b, settings));
    }
  }
  state.counters["pairs"] = static_cast<double>(count);
}
BENCHMARK(BM_StepRemeasure)->Unit(benchmark::kMicrosecond);

void BM_MountSmoothing(benchmark::State& state) {
  // What finish() adds once per run: every frame's factor (its state, the previous frame's and the fifth one
  // back, as the pipeline's references), the priors chosen on up to 600 frames, then one solve over all of them.
  const int frames = static_cast<int>(state.range(0));
  std::mt19937 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<FrameMountFactor> factors;
  for (int i = 5; i < frames; ++i) {
    Eigen::MatrixXd B(9, 9);
    for (Eigen::Index r = 0; r < 9; ++r) {
      for (Eigen::Index c = 0; c < 9; ++c) B(r, c) = normal(rng);
    }
    FrameMountFactor f{{i, i - 1, i - 5}, {}};
    f.factor.information = 1e5 * B * B.transpose();
    f.factor.gradient = Eigen::VectorXd::Zero(9);
    f.factor.linearisation = Eigen::VectorXd::Zero(9);
    for (Eigen::Index a = 0; a < 9; ++a) f.factor.linearisation[a] = a % 3 == 2 ? 0.25 + 0.001 * normal(rng) : 0.005 * normal(rng);
    factors.push_back(std::move(f));
  }
  MountSmoothingSettings settings;
  for (auto _ : state) benchmark::DoNotOptimize(smoothMounts(frames, factors, settings));
}
BENCHMARK(BM_MountSmoothing)->Arg(400)->Arg(5000)->Unit(benchmark::kMillisecond);

const Vocabulary& vocabulary() {
  static const Vocabulary instance = readVocabulary(GROUNDSLAM_DEFAULT_VOCABULARY);
  return instance;
}

void BM_BowTransform(benchmark::State& state) {
  const GroundFeatures a = groundFeatures(frames().first);
  for (auto _ : state) benchmark::DoNotOptimize(vocabulary().transform(a.descriptors));
}
BENCHMARK(BM_BowTransform)->Unit(benchmark::kMillisecond);

void BM_BowQuery(benchmark::State& state) {
  // A database of `places` frames: the HD frame's descriptors with a tenth of the rows replaced at random,
  // so that entries share most words with the query, as places of one floor do.
  const GroundFeatures a = groundFeatures(frames().first);
  BowDatabase database;
  cv::RNG rng(7);
  for (int place = 0; place < state.range(0); ++place) {
    cv::Mat descriptors = a.descriptors.clone();
    for (int row = place % 10; row < descriptors.rows; row += 10) rng.fill(descriptors.row(row), cv::RNG::UNIFORM, 0, 256);
    database.add(place, vocabulary().transform(descriptors));
  }
  const BowVector query = vocabulary().transform(a.descriptors);
  for (auto _ : state) benchmark::DoNotOptimize(database.query(query, 5));
}
BENCHMARK(BM_BowQuery)->Arg(500)->Arg(2000)->Unit(benchmark::kMillisecond);

/// A random walk of `n` poses: odometry edges, and a loop edge from every frame to the one 50 earlier.
PoseGraph walkGraph(int n) {
  PoseGraph graph;
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1e-3);
  graph.addPose(Pose2());
  for (int i = 1; i < n; ++i) {
    const Pose2 step(0.01, 0.0, 0.05 * std::sin(0.01 * i));
    const Pose2 measured(step.x + noise(rng), step.y + noise(rng), step.theta + noise(rng));
    graph.addPose(graph.poses().back() * measured);
    graph.addEdge({i - 1, i, measured, Eigen::Matrix3d::Identity() * 1e6, false});
    if (i >= 50) graph.addEdge({i - 50, i, between(graph.poses()[size_t(i - 50)], graph.poses().back()), Eigen::Matrix3d::Identity() * 1e6, true});
  }
  return graph;
}

void BM_GraphOptimisation(benchmark::State& state) {
  // Whole graph of `n` poses against the default window of its last 100 (graph.window_frames).
  const int n = static_cast<int>(state.range(0));
  const bool window = state.range(1) != 0;
  const PoseGraph original = walkGraph(n);
  for (auto _ : state) {
    state.PauseTiming();
    PoseGraph graph = original;
    state.ResumeTiming();
    benchmark::DoNotOptimize(graph.optimise(window ? n - 100 : 0));
  }
}
BENCHMARK(BM_GraphOptimisation)->Args({1000, 0})->Args({5000, 0})->Args({1000, 1})->Args({5000, 1})->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
