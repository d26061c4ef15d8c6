#include <fstream>
#include <gtest/gtest.h>

#include "TestFiles.hpp"
#include "groundslam/io/ConfigNames.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/InputError.hpp"

using namespace groundslam;
using groundslam::testing::inputErrorOf;

namespace {

const char* kCameraYaml = R"(camera:
  image_width: 1600
  image_height: 1200
  fx: 2195.70853
  fy: 2195.56073
  cx: 820.7289683
  cy: 606.242723
  distortion: [0, 0, 0, 0, 0]
  mounting_height_m: 0.25
dataset:
  map_meters_per_pixel: null
)";

RunSettings load(const std::string& text) {
  ConfigLoader loader;
  loader.applyText(text, "test.yaml");
  return loader.finish();
}

}  // namespace

TEST(ConfigYaml, ReadsTheConventionsCameraFile) {
  const RunSettings settings = load(kCameraYaml);
  const Config& c = settings.config;
  EXPECT_EQ(c.camera.image_width, 1600);
  EXPECT_DOUBLE_EQ(c.camera.fx, 2195.70853);
  EXPECT_DOUBLE_EQ(c.camera.cy, 606.242723);
  EXPECT_FALSE(settings.inputs.map_meters_per_pixel.has_value());
  EXPECT_EQ(settings.inputs.vocabulary, "");
  EXPECT_FALSE(c.camera.T_robot_camera.has_value());
  EXPECT_EQ(c.features.num_features, OrbSettings{}.num_features);  // defaults kept
}

TEST(ConfigYaml, WrittenConfigReadsBackIdentically) {
  RunSettings settings = load(kCameraYaml);
  Config& c = settings.config;
  c.camera.distortion = {0.1, -0.2, 0.001, 0.002, 0.05};
  c.camera.T_robot_camera = std::array<double, 16>{1, 0, 0, 0.1, 0, -1, 0, 0, 0, 0, -1, 0.3, 0, 0, 0, 1};
  settings.inputs.map_meters_per_pixel = 1.25e-4;
  settings.inputs.vocabulary = "/data/floor.gslmvoc";
  c.matching.ratio = 0.55;
  c.odometry.loss = RobustLoss::cauchy;
  const std::string text = configToYaml(settings);
  const RunSettings back = load(text);
  EXPECT_EQ(configToYaml(back), text);
  EXPECT_EQ(back.config.camera.distortion, c.camera.distortion);
  EXPECT_EQ(*back.config.camera.T_robot_camera, *c.camera.T_robot_camera);
  EXPECT_DOUBLE_EQ(*back.inputs.map_meters_per_pixel, 1.25e-4);
  EXPECT_EQ(back.inputs.vocabulary, "/data/floor.gslmvoc");
  EXPECT_EQ(back.config.odometry.loss, RobustLoss::cauchy);
}

TEST(ConfigYaml, LaterLayersOverrideEarlierOnes) {
  ConfigLoader loader;
  loader.applyText(kCameraYaml, "camera.yaml");
  loader.applyText("matching:\n  ratio: 0.6\ncamera:\n  fx: 1000\n", "override.yaml");
  const Config c = loader.finish().config;
  EXPECT_DOUBLE_EQ(c.matching.ratio, 0.6);
  EXPECT_DOUBLE_EQ(c.camera.fx, 1000.0);
  EXPECT_DOUBLE_EQ(c.camera.fy, 2195.56073);
}

TEST(ConfigYaml, UnknownKeyIsNamedWithItsLine) {
  const std::string message = inputErrorOf([] { load(std::string(kCameraYaml) + "matching:\n  ratio_threshold: 0.5\n"); });
  EXPECT_NE(message.find("test.yaml:13"), std::string::npos) << message;
  EXPECT_NE(message.find("matching.ratio_threshold"), std::string::npos) << message;
  EXPECT_NE(message.find("unknown key"), std::string::npos) << message;
  EXPECT_NE(inputErrorOf([] { load(std::string(kCameraYaml) + "magic:\n  x: 1\n"); }).find("unknown section"),
            std::string::npos);
}

TEST(ConfigYaml, BadValuesAreNamed) {
  auto replace = [](std::string text, const std::string& from, const std::string& to) {
    return text.replace(text.find(from), from.size(), to);
  };
  std::string m = inputErrorOf([&] { load(replace(kCameraYaml, "fx: 2195.70853", "fx: fast")); });
  EXPECT_NE(m.find("camera.fx"), std::string::npos) << m;
  EXPECT_NE(m.find("test.yaml:4"), std::string::npos) << m;
  m = inputErrorOf([&] { load(replace(kCameraYaml, "fx: 2195.70853", "fx: -3")); });
  EXPECT_NE(m.find("out of range"), std::string::npos) << m;
  m = inputErrorOf([&] { load(replace(kCameraYaml, "image_width: 1600", "image_width: 16.5")); });
  EXPECT_NE(m.find("camera.image_width"), std::string::npos) << m;
  m = inputErrorOf([&] { load(replace(kCameraYaml, "[0, 0, 0, 0, 0]", "[0, 0, 0]")); });
  EXPECT_NE(m.find("camera.distortion"), std::string::npos) << m;
  m = inputErrorOf([&] { load(std::string(kCameraYaml) + "odometry:\n  loss: l2\n"); });
  EXPECT_NE(m.find("odometry.loss"), std::string::npos) << m;
  EXPECT_NE(m.find("huber"), std::string::npos) << m;
}

TEST(ConfigYaml, EnumValuesAreReadByName) {
  ConfigLoader loader;
  loader.applyText(kCameraYaml, "camera.yaml");
  loader.applyText("camera:\n  distortion_model: equidistant\nfeatures:\n  score_type: fast\nmatching:\n  method: lsh\n"
                   "odometry:\n  loss: geman_mcclure\n", "names.yaml");
  const Config c = loader.finish().config;
  EXPECT_EQ(c.camera.distortion_model, DistortionModel::equidistant);
  EXPECT_EQ(c.features.score_type, OrbScore::fast);
  EXPECT_EQ(c.matching.method, MatcherMethod::lsh);
  EXPECT_EQ(c.odometry.loss, RobustLoss::geman_mcclure);
  const std::string m = inputErrorOf([] { load(std::string(kCameraYaml) + "matching:\n  method: LSH\n"); });
  EXPECT_NE(m.find("key 'matching.method': 'LSH' is not one of: brute_force, lsh"), std::string::npos) << m;
  // Every name reads back to its value, and a value the enum does not declare has no name.
  for (const auto& [value, name] : namesOf(RobustLoss{})) EXPECT_EQ(valueNamed<RobustLoss>(name), value);
  EXPECT_EQ(nameOf(static_cast<RobustLoss>(7)), "?");
}

TEST(ConfigYaml, MissingRequiredKeyIsNamed) {
  const std::string text = std::string(kCameraYaml).replace(std::string(kCameraYaml).find("  cy: 606.242723\n"), 17, "");
  const std::string m = inputErrorOf([&] { load(text); });
  EXPECT_NE(m.find("camera.cy"), std::string::npos) << m;
  EXPECT_NE(inputErrorOf([] { load(""); }).find("camera.image_width"), std::string::npos);
}

TEST(ConfigYaml, MissingFileAndBrokenYamlAreNamed) {
  EXPECT_NE(inputErrorOf([] { loadConfig({"/nonexistent/cfg.yaml"}); }).find("/nonexistent/cfg.yaml"), std::string::npos);
  const std::string m = inputErrorOf([] { load("camera: [1, 2\n"); });
  EXPECT_NE(m.find("test.yaml"), std::string::npos) << m;
  EXPECT_NE(m.find("invalid YAML"), std::string::npos) << m;
}

TEST(ConfigYaml, ShippedDefaultFileMatchesTheDefaultsInCode) {
  const RunSettings shipped = loadConfig({std::string(GROUNDSLAM_SOURCE_DIR) + "/config/default.yaml"});
  RunSettings expected;
  expected.config.camera = shipped.config.camera;  // the file shows HD Ground's camera; the rest must be the defaults
  EXPECT_EQ(configToYaml(shipped), configToYaml(expected));
  EXPECT_DOUBLE_EQ(shipped.config.camera.fx, 2195.70853);
  // Every key is in the file, written as groundslam writes it (comment lines aside), and has a comment.
  std::ifstream file(std::string(GROUNDSLAM_SOURCE_DIR) + "/config/default.yaml");
  std::string text, line;
  std::string previous;
  while (std::getline(file, line)) {
    const bool comment = line.find_first_not_of(' ') != std::string::npos && line[line.find_first_not_of(' ')] == '#';
    if (!comment) {
      text += line + "\n";
      if (line.rfind("  ", 0) == 0) {
        EXPECT_NE(previous.find("  # "), std::string::npos) << "key without a comment: " << line;
      }
    }
    previous = line;
  }
  EXPECT_EQ(text, configToYaml(shipped));
}


TEST(ConfigYaml, ASearchStepBelowADegreeIsRefusedWithItsKey) {
  // bridge_search_turn_deg tries a turn every so many degrees round the circle: 0.5 would try 720 per usual step.
  std::string m = inputErrorOf([&] { load(std::string(kCameraYaml) + "odometry:\n  bridge_search_turn_deg: 0.5\n"); });
  EXPECT_NE(m.find("odometry.bridge_search_turn_deg"), std::string::npos) << m;
  m = inputErrorOf([&] { load(std::string(kCameraYaml) + "odometry:\n  bridge_search_turn_deg: 45\n"); });
  EXPECT_NE(m.find("odometry.bridge_search_turn_deg"), std::string::npos) << m;
  EXPECT_NO_THROW(load(std::string(kCameraYaml) + "odometry:\n  bridge_search_turn_deg: 0\n"));
  EXPECT_NO_THROW(load(std::string(kCameraYaml) + "odometry:\n  bridge_search_turn_deg: 1\n"));
}

TEST(ConfigYaml, AHeadingImageNarrowerThan16PixelsIsRefusedWithItsKey) {
  // 0 turns the outdoor heading images off; otherwise they must be as wide as the alignment's own images at least.
  const std::string m = inputErrorOf([&] { load(std::string(kCameraYaml) + "outdoor:\n  heading_image_width_px: 8\n"); });
  EXPECT_NE(m.find("outdoor.heading_image_width_px"), std::string::npos) << m;
  EXPECT_NO_THROW(load(std::string(kCameraYaml) + "outdoor:\n  heading_image_width_px: 0\n"));
  EXPECT_NO_THROW(load(std::string(kCameraYaml) + "outdoor:\n  heading_image_width_px: 16\n"));
}
