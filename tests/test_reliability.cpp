// Crafted bad inputs (kept under tests/data/) and the fault cases of run folders: each must end in a clear
// error naming the file, line or key, never a crash, a hang or a silently wrong result.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "TestFiles.hpp"
#include "groundslam/eval/TrajectoryMetrics.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/Dataset.hpp"
#include "groundslam/io/Files.hpp"
#include "groundslam/io/ImageFile.hpp"
#include "groundslam/io/RunFolder.hpp"
#include "groundslam/io/VocabularyFile.hpp"
#include "groundslam/pipeline/Slam.hpp"

using namespace groundslam;
using groundslam::testing::inputErrorOf;
using groundslam::testing::scratchDir;
using groundslam::testing::writeText;
namespace fs = std::filesystem;

namespace {

std::string dataFile(const std::string& relative) { return std::string(GROUNDSLAM_SOURCE_DIR) + "/tests/data/" + relative; }

std::string configErrorOf(const std::string& crafted) {
  return inputErrorOf([&] { loadConfig({dataFile("config/camera.yaml"), dataFile("config/" + crafted)}); });
}

std::string listErrorOf(const std::string& crafted) {
  const std::string path = dataFile("lists/" + crafted);
  return inputErrorOf([&] { parseHdGroundList(readTextFile(path), path, true); });
}

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

TEST(CraftedVocabulary, BrokenTreesWithAValidChecksumAreRefusedWithTheReason) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"child_index_overflow", "child index 2147483647 is out of range"},
      {"node_is_its_own_child", "node 0: child index 0 is out of range"},
      {"two_node_cycle", "node 1: child index 0 is out of range"},
      {"child_points_back", "node 1: child index 1 is out of range"},
      {"negative_child_count", "child count -1"},
      {"nan_idf", "word 0 has IDF weight nan"},
      {"no_nodes", "the tree has no nodes"},
      {"leaf_word_out_of_range", "node 2: leaf word 5 is out of range"},
      {"no_words", "the vocabulary has no words"},
      {"deeper_than_depth", "deeper than its depth 1"},
  };
  for (const auto& [name, reason] : cases) {
    const std::string message = inputErrorOf([&] { readVocabulary(dataFile("vocabulary/" + name + ".gslmvoc")); });
    EXPECT_NE(message.find(name + ".gslmvoc: vocabulary file is inconsistent"), std::string::npos) << message;
    EXPECT_NE(message.find(reason), std::string::npos) << name << ": " << message;
  }
  const Vocabulary valid = readVocabulary(dataFile("vocabulary/valid_two_words.gslmvoc"));
  std::array<std::uint8_t, 32> ones;
  ones.fill(0xFF);
  EXPECT_EQ(valid.wordOf(ones.data()), 1);
}

TEST(CraftedConfig, NumbersThatDoNotFitTheirKeyAreNamedWithFileAndLine) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"int_1e30.yaml", "int_1e30.yaml:2: key 'features.num_features': value 1e+30 out of range [10, 100000]"},
      {"int_nan.yaml", "int_nan.yaml:2: key 'features.num_levels': expected an integer, got '.nan'"},
      {"int_inf.yaml", "int_inf.yaml:2: key 'features.num_levels': expected an integer, got '.inf'"},
      {"image_width_1e10.yaml", "key 'camera.image_width': value 10000000000 out of range (0, 2147483647]"},
      {"seed_1e10.yaml", "seed_1e10.yaml:2: key 'odometry.seed': value 10000000000 out of range [0, 2147483647]"},
      {"fx_inf.yaml", "fx_inf.yaml:2: key 'camera.fx': '.inf' is not a finite number"},
      {"cx_minus_inf.yaml", "key 'camera.cx': '-.inf' is not a finite number"},
      {"distortion_inf.yaml", "key 'camera.distortion': '.inf' is not a finite number"},
      {"mounting_height_inf.yaml", "key 'camera.mounting_height_m': '.inf' is not a finite number"},
      {"map_scale_inf.yaml", "key 'dataset.map_meters_per_pixel': '.inf' is not a finite number"},
      {"mount_inf.yaml", "key 'camera.T_robot_camera': '.inf' is not a finite number"},
      {"mount_all_zero.yaml", "mount_all_zero.yaml:2: key 'camera.T_robot_camera': not a rigid transform"},
      {"mount_upward.yaml", "mount_upward.yaml:3: key 'camera.T_robot_camera': part of the image does not look at the ground"},
      {"mount_below_ground.yaml", "key 'camera.T_robot_camera': the camera is not above the ground"},
      {"pyramid_too_deep.yaml", "pyramid_too_deep.yaml:2: key 'features.num_levels': 16 levels with scale_factor 4 shrink"},
      {"scalar_root.yaml", "scalar_root.yaml:1: expected a YAML mapping of sections"},
      {"list_as_key.yaml", "list_as_key.yaml:2: key 'camera.?': a key must be a plain name"},
      {"duplicate_key.yaml", "duplicate_key.yaml:3: key 'features.num_features': key given twice"},
      {"duplicate_section.yaml", "duplicate_section.yaml:3: key 'features': section given twice"},
      {"second_document.yaml", "second_document.yaml:3: a second YAML document"},
  };
  for (const auto& [file, expected] : cases) {
    const std::string message = configErrorOf(file);
    EXPECT_NE(message.find(expected), std::string::npos) << file << ": " << message;
  }
}

TEST(CraftedConfig, AFolderIsNotAConfigurationFile) {
  const fs::path dir = scratchDir();
  EXPECT_NE(inputErrorOf([&] { loadConfig({dir.string()}); }).find("not a configuration file"), std::string::npos);
}

TEST(CraftedConfig, SlamRefusesAConfigurationBuiltInCodeWithTheKeyNamed) {
  Config config;  // no camera: fx = 0
  try {
    Slam slam(config, nullptr);
    FAIL() << "accepted fx = 0";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("camera.image_width: value 0 out of range", 0), 0u) << e.what();
  }
  config = loadConfig({dataFile("config/camera.yaml")}).config;
  config.camera.fx = std::numeric_limits<double>::infinity();
  EXPECT_NE(inputErrorOf([&] { Slam slam(config, nullptr); }).find("camera.fx: value inf is not a finite number"), std::string::npos);
  config = loadConfig({dataFile("config/camera.yaml")}).config;
  config.odometry.loss = static_cast<RobustLoss>(9);  // no such loss: refused, not a silent default
  EXPECT_NE(inputErrorOf([&] { Slam slam(config, nullptr); }).find("odometry.loss: value 9 is not one of the enum's values"),
            std::string::npos);
}

TEST(CraftedConfig, RelativeVocabularyIsFoundBesideItsConfigFile) {
  const fs::path dir = scratchDir();
  fs::create_directories(dir / "configs");
  writeText(dir / "configs" / "lc.yaml", "loop_closure:\n  vocabulary: ../vocab/floor.gslmvoc\n");
  const RunSettings settings = loadConfig({dataFile("config/camera.yaml"), (dir / "configs" / "lc.yaml").string()});
  EXPECT_EQ(settings.inputs.vocabulary, fs::absolute(dir / "vocab" / "floor.gslmvoc").lexically_normal().string());
}

TEST(CraftedList, PoseMatricesThatAreNoPoseAreRefusedWithTheirLine) {
  EXPECT_NE(listErrorOf("zero_pose.txt").find("zero_pose.txt:2: pose matrix has a last row other than 0 0 1"), std::string::npos);
  EXPECT_NE(listErrorOf("huge_pose.txt").find("huge_pose.txt:2: pose matrix scales image pixels by"), std::string::npos);
  EXPECT_NE(listErrorOf("denormal_pose.txt").find("denormal_pose.txt:2: pose matrix has a last row"), std::string::npos);
  EXPECT_NE(listErrorOf("far_translation.txt").find("far_translation.txt:2: pose matrix has a translation beyond"), std::string::npos);
  EXPECT_NE(listErrorOf("mirrored_pose.txt").find("mirrored_pose.txt:2: pose matrix is singular or mirrored"), std::string::npos);
}

TEST(CraftedList, ByteOrderMarkAndTabAfterTheUnreliableMarkAreRead) {
  const std::string path = dataFile("lists/bom_and_tab_unreliable.txt");
  const auto entries = parseHdGroundList(readTextFile(path), path, true);
  ASSERT_EQ(entries.size(), 2u);
  EXPECT_EQ(entries[0].image, "a.png");
  EXPECT_TRUE(entries[0].pose_reliable);
  EXPECT_EQ(entries[1].image, "b.png");
  EXPECT_FALSE(entries[1].pose_reliable);
  EXPECT_DOUBLE_EQ((*entries[1].map_from_image)(0, 2), 6.0);
}

TEST(CraftedList, AHugePathLineIsReportedWithItsLineNumber) {
  const std::string text = "a.png\n1 0 5 0 1 7 0 0 1\n" + std::string(2 << 20, 'x') + ".png\n1 0 5 0 1 7 0 0 1\n";
  EXPECT_NE(inputErrorOf([&] { parseHdGroundList(text, "big.txt", true); }).find("big.txt:3: image path is 2097156 characters long"),
            std::string::npos);
}

TEST(Images, SixteenBitFilesAreScaledByTheirSignificantBits) {
  const fs::path dir = scratchDir();
  cv::Mat eight_in_sixteen(24, 32, CV_16U, cv::Scalar(200)), twelve_bit(24, 32, CV_16U, cv::Scalar(1000));
  twelve_bit.at<std::uint16_t>(0, 0) = 4095;
  cv::imwrite((dir / "eight.png").string(), eight_in_sixteen);
  cv::imwrite((dir / "twelve.png").string(), twelve_bit);
  EXPECT_EQ(loadGrayImage((dir / "eight.png").string(), 32, 24).at<std::uint8_t>(5, 5), 200);
  const cv::Mat twelve = loadGrayImage((dir / "twelve.png").string(), 32, 24);
  EXPECT_EQ(twelve.at<std::uint8_t>(0, 0), 255);
  EXPECT_EQ(twelve.at<std::uint8_t>(5, 5), 62);  // 1000 * 255 / 4095 = 62.3
}

TEST(Images, AHugeImageIsRefusedFromItsHeaderBeforeDecoding) {
  const fs::path dir = scratchDir();
  // A PNG signature and an IHDR claiming 20000 x 15000, and nothing else: decoding it would fail differently.
  const unsigned char header[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R',
                                  0, 0, 0x4E, 0x20, 0, 0, 0x3A, 0x98, 8, 0, 0, 0, 0};
  std::ofstream(dir / "huge.png", std::ios::binary).write(reinterpret_cast<const char*>(header), sizeof(header));
  EXPECT_NE(inputErrorOf([&] { loadGrayImage((dir / "huge.png").string(), 320, 240); }).find("huge.png: image is 20000x15000"),
            std::string::npos);
  cv::imwrite((dir / "small.jpg").string(), cv::Mat(24, 32, CV_8U, cv::Scalar(90)));
  cv::imwrite((dir / "small.bmp").string(), cv::Mat(24, 32, CV_8U, cv::Scalar(90)));
  cv::imwrite((dir / "small.pgm").string(), cv::Mat(24, 32, CV_8U, cv::Scalar(90)));
  for (const char* name : {"small.jpg", "small.bmp", "small.pgm"}) {
    const auto size = imageSizeFromHeader((dir / name).string());
    ASSERT_TRUE(size.has_value()) << name;
    EXPECT_EQ(*size, cv::Size(32, 24)) << name;
  }
}

TEST(Metrics, NothingToCompareIsNotAPerfectScore) {
  const Trajectory truth = {{0.0, Pose2()}, {1.0, Pose2(1, 0, 0)}};
  const Trajectory elsewhere = {{5.0, Pose2()}, {6.0, Pose2(1, 0, 0)}};
  const TrajectoryMetrics m = evaluateTrajectory(truth, elsewhere).metrics;
  EXPECT_EQ(m.paired_frames, 0);
  EXPECT_TRUE(std::isnan(m.ate_rmse_m));
  EXPECT_TRUE(std::isnan(m.translation_mae_cm_per_m));
  const std::string json = metricsToJson(m);
  EXPECT_NE(json.find("\"ate_rmse_m\": null"), std::string::npos) << json;
  EXPECT_EQ(json.find("nan"), std::string::npos) << json;
  EXPECT_NE(metricsToText(m).find("ATE RMSE (SE2-aligned) n/a"), std::string::npos);
}

TEST(Metrics, FallbackPosesAreNotCountedAsMeasured) {
  const Trajectory truth = {{0.0, Pose2()}, {1.0, Pose2(0.01, 0, 0)}, {2.0, Pose2(0.02, 0, 0)}, {3.0, Pose2(0.03, 0, 0)}};
  Trajectory estimate = truth;
  estimate[2].measured = estimate[3].measured = false;
  const TrajectoryMetrics m = evaluateTrajectory(truth, estimate).metrics;
  EXPECT_EQ(m.paired_frames, 4);
  EXPECT_EQ(m.measured_frames, 2);
  EXPECT_DOUBLE_EQ(m.fraction_measured, 0.5);
  EXPECT_NE(metricsToText(m).find("frames measured       2 / 4 (50.0%; 2 more with a pose assumed"), std::string::npos);
}

TEST(Files, NewFilesNeverFollowOrReplaceWhatIsThere) {
  const fs::path dir = scratchDir();
  writeText(dir / "target.txt", "precious");
  fs::create_symlink(dir / "target.txt", dir / "link.txt");
  EXPECT_NE(inputErrorOf([&] { writeNewFile((dir / "link.txt").string(), "overwrite"); }).find("exists already"), std::string::npos);
  EXPECT_EQ(slurp(dir / "target.txt"), "precious");
  // Atomic writes replace a symbolic link itself, never the file it points to.
  writeFileAtomically((dir / "link.txt").string(), "new");
  EXPECT_EQ(slurp(dir / "target.txt"), "precious");
  EXPECT_EQ(slurp(dir / "link.txt"), "new");
  EXPECT_FALSE(fs::is_symlink(dir / "link.txt"));
  EXPECT_NE(inputErrorOf([&] { writeNewFile((dir / "no" / "such" / "x.txt").string(), "x"); }).find("No such file or directory"),
            std::string::npos);
}

TEST(RunFolders, ResultsReplaceTheTargetOnlyOnCommit) {
  const fs::path dir = scratchDir();
  const std::string target = (dir / "run").string();
  {
    RunFolder first(target, {});
    writeNewFile(first.path("trajectory.tum"), "first");
    first.commit();
  }
  {
    RunFolder failed(target, {});
    writeNewFile(failed.path("trajectory.tum"), "failed");
  }  // not committed: the run failed
  EXPECT_EQ(slurp(dir / "run" / "trajectory.tum"), "first");
  {
    RunFolder second(target, {});
    writeNewFile(second.path("frames.csv"), "second");
    second.commit();
  }
  EXPECT_EQ(slurp(dir / "run" / "frames.csv"), "second");
  EXPECT_FALSE(fs::exists(dir / "run" / "trajectory.tum"));  // results never mix two runs
  {
    RunFolder interrupted(target, {});
    writeNewFile(interrupted.path("frames.csv"), "partial");
    EXPECT_EQ(interrupted.commitPartial(), target + ".interrupted");
  }
  EXPECT_EQ(slurp(dir / "run" / "frames.csv"), "second");
  EXPECT_EQ(slurp(dir / "run.interrupted" / "frames.csv"), "partial");
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
  EXPECT_EQ(left.size(), 2u);  // run and run.interrupted: no staging folder left behind
}

TEST(RunFolders, FoldersWithOtherFilesAndInputsInsideAreRefused) {
  const fs::path dir = scratchDir();
  fs::create_directories(dir / "dataset");
  writeText(dir / "dataset" / "sequence.txt", "a.png\n");
  writeText(dir / "dataset" / "groundtruth.tum", "0 0 0 0 0 0 0 1\n");
  EXPECT_NE(inputErrorOf([&] { RunFolder f((dir / "dataset").string(), {}); }).find("holds files a run does not write (sequence.txt"),
            std::string::npos);
  fs::create_directories(dir / "old_run");
  writeText(dir / "old_run" / "config.yaml", "camera: {}\n");
  EXPECT_NE(inputErrorOf([&] { RunFolder f((dir / "old_run").string(), {(dir / "old_run" / "config.yaml").string()}); })
                .find("an input of this run"),
            std::string::npos);
  EXPECT_EQ(slurp(dir / "dataset" / "groundtruth.tum"), "0 0 0 0 0 0 0 1\n");
}

TEST(RunFolders, NewFolderNamesAndTheLatestLink) {
  const fs::path dir = scratchDir();
  const std::string first = newRunFolderName(dir.string());
  fs::create_directories(first);
  const std::string second = newRunFolderName(dir.string());
  EXPECT_NE(first, second);
  EXPECT_TRUE(pointLatestAt(dir.string(), first));
  EXPECT_EQ(fs::read_symlink(dir / "latest"), fs::path(first).filename());
  fs::remove(dir / "latest");
  fs::create_directories(dir / "latest");
  EXPECT_FALSE(pointLatestAt(dir.string(), first));  // a real folder named latest is left alone
}
