// `groundslam simulate` then `groundslam run` through the command line, as a user would.
#include <cstdlib>
#include <fstream>
#include <regex>

#include <gtest/gtest.h>

#include "TestFiles.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/Files.hpp"
#include "groundslam/io/Tum.hpp"

using namespace groundslam;
using groundslam::testing::scratchDir;

namespace {

int runCli(const std::string& args) {
  return std::system((std::string(GROUNDSLAM_BINARY) + " " + args + " > /dev/null 2>&1").c_str());
}

double jsonNumber(const std::string& json, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\"" + key + "\": ([-0-9.eE+]+)"))) return std::nan("");
  return std::stod(m[1]);
}

}  // namespace

TEST(EndToEnd, OdometryOnAPerturbedSequenceStaysAccurate) {
  const auto dir = scratchDir();
  ASSERT_EQ(runCli("simulate " + (dir / "seq").string() +
                   " --texture-kind concrete --path loop --frames 150 --jitter-deg 0.5 --motion-blur 0.3"
                   " --defocus-px 0.6 --noise 2 --exposure-variation 0.15 --vignetting 0.2 --seed 3"),
            0);
  ASSERT_EQ(runCli("run " + (dir / "seq" / "sequence.txt").string() + " --out " + (dir / "run").string()), 0);
  const auto run = dir / "run";
  EXPECT_EQ(readTum((run / "trajectory.tum").string()).size(), 150u);
  EXPECT_EQ(readTum((run / "groundtruth.tum").string()).size(), 150u);
  const std::string frames = readTextFile((run / "frames.csv").string());
  EXPECT_EQ(frames.substr(0, frames.find('\n')),
            "index,timestamp,keypoints,matches,inliers,status,load_ms,extract_ms,project_ms,match_ms,fit_ms,loop_ms,"
            "optimise_ms,total_ms");
  EXPECT_EQ(frames.find("fallback"), std::string::npos) << "odometry must keep every frame";
  const Config config = loadConfig({(run / "config.yaml").string()});  // the effective config reads back
  EXPECT_EQ(config.camera.image_width, 320);
  const std::string metrics = readTextFile((run / "metrics.json").string());
  EXPECT_DOUBLE_EQ(jsonNumber(metrics, "fraction_estimated"), 1.0);
  // Measured 0.23 cm/m and 1.03 deg (odometry alone; the 0.5 degree rocking of the mount dominates);
  // the bounds catch a regression, not noise.
  EXPECT_LT(jsonNumber(metrics, "translation_mae_cm_per_m"), 0.35);
  EXPECT_LT(jsonNumber(metrics, "rotation_mae_deg"), 1.6);
  EXPECT_LT(jsonNumber(metrics, "rpe_translation_rmse_m"), 0.0025);

  // `evaluate` on the written files gives the same numbers.
  ASSERT_EQ(runCli("evaluate " + (run / "groundtruth.tum").string() + " " + (run / "trajectory.tum").string() +
                   " --json " + (dir / "again.json").string()),
            0);
  EXPECT_EQ(readTextFile((dir / "again.json").string()), metrics);
}
