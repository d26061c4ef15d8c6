#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "TestFiles.hpp"
#include "groundslam/io/Dataset.hpp"
#include "groundslam/io/Files.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/RunFiles.hpp"
#include "groundslam/io/TextParsing.hpp"
#include "groundslam/io/Tum.hpp"

using namespace groundslam;
using groundslam::testing::inputErrorOf;
using groundslam::testing::scratchDir;
using groundslam::testing::writeText;

namespace {

void writeImage(const std::filesystem::path& path, int w = 32, int h = 24) {
  cv::imwrite(path.string(), cv::Mat(h, w, CV_8U, cv::Scalar(128)));
}

}  // namespace

TEST(HdGround, PoseFromHomographyFollowsConventions) {
  // A = identity: the principal point maps to map pixel (cx, cy): x = s cx, y = -s cy, theta = 0.
  const Pose2 p = robotPoseFromMapHomography(Eigen::Matrix3d::Identity(), 800.0, 600.0, 0.001);
  EXPECT_NEAR(p.x, 0.8, 1e-12);
  EXPECT_NEAR(p.y, -0.6, 1e-12);
  EXPECT_NEAR(p.theta, 0.0, 1e-12);
  // A rotation of the image by +30 degrees in the map (map y down) is a robot heading of +30 degrees.
  const double a = 30.0 * M_PI / 180.0;
  Eigen::Matrix3d A;
  A << std::cos(a), std::sin(a), 100.0, -std::sin(a), std::cos(a), 50.0, 0.0, 0.0, 1.0;
  EXPECT_NEAR(robotPoseFromMapHomography(A, 0.0, 0.0, 0.002).theta, a, 1e-12);
  EXPECT_NEAR(robotPoseFromMapHomography(A, 0.0, 0.0, 0.002).y, -0.1, 1e-12);
}

TEST(HdGround, HomographyOfAPoseRoundTrips) {
  CameraIntrinsics k;
  k.width = 1600, k.height = 1200, k.fx = 2195.70853, k.fy = 2195.56073, k.cx = 820.7289683, k.cy = 606.242723;
  const double s = 0.25 / k.fx;
  for (const Pose2& pose : {Pose2(0.3, -1.2, 2.5), Pose2(-4.0, 0.01, -M_PI + 1e-4), Pose2(0, 0, M_PI)}) {
    const Pose2 back = robotPoseFromMapHomography(mapHomographyFromRobotPose(pose, k, s), k.cx, k.cy, s);
    EXPECT_NEAR(back.x, pose.x, 1e-12);
    EXPECT_NEAR(back.y, pose.y, 1e-12);
    EXPECT_NEAR(wrapAngle(back.theta - pose.theta), 0.0, 1e-12);
  }
}

TEST(HdGround, ReadsListWithRelativePathsUnreliableLinesAndCameraYaml) {
  const auto dir = scratchDir();
  std::filesystem::create_directories(dir / "seq" / "img");
  writeImage(dir / "seq" / "img" / "a.png");
  writeImage(dir / "seq" / "img" / "b.png");
  writeText(dir / "seq" / "camera.yaml", "camera: {}\n");
  writeText(dir / "seq" / "path1.txt", "img/a.png\n1 0 10 0 1 20 0 0 1\nimg/b.png\n* 1 0 11 0 1 20 0 0 1\n");
  const Dataset d = openDataset((dir / "seq" / "path1.txt").string());
  ASSERT_EQ(d.frames.size(), 2u);
  EXPECT_EQ(d.frames[1].image_path, (dir / "seq" / "img" / "b.png").string());
  EXPECT_TRUE(d.frames[0].pose_reliable);
  EXPECT_FALSE(d.frames[1].pose_reliable);
  EXPECT_DOUBLE_EQ((*d.frames[1].map_from_image)(0, 2), 11.0);
  EXPECT_DOUBLE_EQ(d.frames[1].timestamp, 1.0);
  ASSERT_TRUE(d.camera_yaml.has_value());
  EXPECT_TRUE(d.hasGroundTruth());

  writeText(dir / "seq" / "path1.test", "img/a.png\nimg/b.png\n");
  const Dataset t = openDataset((dir / "seq" / "path1.test").string());
  EXPECT_EQ(t.frames.size(), 2u);
  EXPECT_FALSE(t.hasGroundTruth());
}

TEST(HdGround, MalformedListsAreNamedWithTheirLine) {
  const auto dir = scratchDir();
  writeImage(dir / "a.png");
  writeText(dir / "short.txt", "a.png\n1 0 0 0 1 0 0 1\n");
  std::string m = inputErrorOf([&] { openDataset((dir / "short.txt").string()); });
  EXPECT_NE(m.find("short.txt:2"), std::string::npos) << m;
  EXPECT_NE(m.find("expected 9 numbers"), std::string::npos) << m;
  writeText(dir / "word.txt", "a.png\n1 0 0 0 one 0 0 0 1\n");
  m = inputErrorOf([&] { openDataset((dir / "word.txt").string()); });
  EXPECT_NE(m.find("word.txt:2: not a number: 'one'"), std::string::npos) << m;
  writeText(dir / "missing.txt", "a.png\n1 0 0 0 1 0 0 0 1\nnothere.png\n1 0 0 0 1 0 0 0 1\n");
  m = inputErrorOf([&] { openDataset((dir / "missing.txt").string()); });
  EXPECT_NE(m.find("missing.txt:3"), std::string::npos) << m;
  EXPECT_NE(m.find("nothere.png"), std::string::npos) << m;
  writeText(dir / "dangling.txt", "a.png\n1 0 0 0 1 0 0 0 1\na.png\n");
  EXPECT_NE(inputErrorOf([&] { openDataset((dir / "dangling.txt").string()); }).find("dangling.txt:3: image without a pose"),
            std::string::npos);
  // Only image paths: a plain list of images, no ground truth.
  writeImage(dir / "b.png");
  writeText(dir / "plain.txt", "a.png\nb.png\n\na.png\n");
  const Dataset plain = openDataset((dir / "plain.txt").string());
  ASSERT_EQ(plain.frames.size(), 3u);
  EXPECT_EQ(std::filesystem::path(plain.frames[1].image_path).filename(), "b.png");
  EXPECT_FALSE(plain.hasGroundTruth());
  EXPECT_NE(inputErrorOf([&] { openDataset((dir / "nope.txt").string()); }).find("nope.txt"), std::string::npos);
}

TEST(ImageFolder, NaturalSortOrder) {
  const auto dir = scratchDir();
  for (const char* name : {"frame10.png", "frame2.png", "frame1.png"}) writeImage(dir / name);
  writeText(dir / "notes.md", "not an image");
  const Dataset d = openDataset(dir.string());
  ASSERT_EQ(d.frames.size(), 3u);
  EXPECT_EQ(std::filesystem::path(d.frames[0].image_path).filename(), "frame1.png");
  EXPECT_EQ(std::filesystem::path(d.frames[1].image_path).filename(), "frame2.png");
  EXPECT_EQ(std::filesystem::path(d.frames[2].image_path).filename(), "frame10.png");
  EXPECT_FALSE(d.hasGroundTruth());
  EXPECT_TRUE(naturalLess("img9_b", "img10_a"));
  EXPECT_FALSE(naturalLess("img10", "img9"));
}

TEST(Images, UndecodableAndWrongSizeImagesAreNamed) {
  const auto dir = scratchDir();
  writeText(dir / "broken.png", "not a png");
  writeImage(dir / "small.png", 32, 24);
  EXPECT_NE(inputErrorOf([&] { loadGrayImage((dir / "broken.png").string(), 32, 24); }).find("broken.png: image does not decode"),
            std::string::npos);
  const std::string m = inputErrorOf([&] { loadGrayImage((dir / "small.png").string(), 64, 48); });
  EXPECT_NE(m.find("small.png: image is 32x24"), std::string::npos) << m;
  EXPECT_EQ(loadGrayImage((dir / "small.png").string(), 32, 24).at<unsigned char>(3, 3), 128);
}

TEST(Tum, WritesTheConventionsFormatAndReadsItBack) {
  const auto dir = scratchDir();
  const std::vector<StampedPose> poses = {{0.0, Pose2(1.0, 2.0, 0.0)}, {1.5, Pose2(-0.5, 0.25, M_PI)},
                                          {3.0, Pose2(0.1, 0.2, -2.0)}};
  writeTum((dir / "t.tum").string(), poses);
  EXPECT_FALSE(std::filesystem::exists(dir / "t.tum.partial"));
  const std::string text = readTextFile((dir / "t.tum").string());
  EXPECT_EQ(text.substr(0, text.find('\n')), "0.000000000 1.000000000000 2.000000000000 0 0 0 0.000000000000 1.000000000000");
  const auto back = readTum((dir / "t.tum").string());
  ASSERT_EQ(back.size(), 3u);
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_DOUBLE_EQ(back[i].timestamp, poses[i].timestamp);
    EXPECT_NEAR(back[i].T_world_robot.x, poses[i].T_world_robot.x, 1e-9);
    EXPECT_NEAR(wrapAngle(back[i].T_world_robot.theta - poses[i].T_world_robot.theta), 0.0, 1e-11);
  }
  writeText(dir / "bad.tum", "0 1 2 0 0 0 0 1\n1 1 2 0 0 0 1\n");
  EXPECT_NE(inputErrorOf([&] { readTum((dir / "bad.tum").string()); }).find("bad.tum:2: expected 8 numbers"), std::string::npos);
}

TEST(Timestamps, FromNumericFileNamesIntoTheTrajectory) {
  const auto dir = scratchDir();
  for (const char* name : {"1700000000.133.png", "1700000000.2.png", "1700000001.png"}) writeImage(dir / name);
  const Dataset dataset = openDataset(dir.string());
  EXPECT_EQ(dataset.timestamps_from, "file names");
  ASSERT_EQ(dataset.frames.size(), 3u);
  EXPECT_DOUBLE_EQ(dataset.frames[0].timestamp, 1700000000.133);
  EXPECT_DOUBLE_EQ(dataset.frames[1].timestamp, 1700000000.2);
  EXPECT_DOUBLE_EQ(dataset.frames[2].timestamp, 1700000001.0);
  // TUM keeps them to the nanosecond (evo pairs trajectories by time): 1700000000.132999897, the double nearest.
  const std::string tum = formatTum({{dataset.frames[0].timestamp, Pose2()}});
  EXPECT_NEAR(std::stod(tum.substr(0, tum.find(' '))), 1700000000.133, 1e-6);
}

TEST(Timestamps, TimestampsFileWinsAndIsChecked) {
  const auto dir = scratchDir();
  for (const char* name : {"a.png", "b.png", "c.png"}) writeImage(dir / name);
  EXPECT_EQ(openDataset(dir.string()).timestamps_from, "index");  // names that are not numbers: the index
  writeText(dir / "timestamps.txt", "# seconds\n12.5\n12.75\n\n13.0\n");
  const Dataset dataset = openDataset(dir.string());
  EXPECT_EQ(dataset.timestamps_from, (dir / "timestamps.txt").string());
  EXPECT_DOUBLE_EQ(dataset.frames[1].timestamp, 12.75);
  EXPECT_DOUBLE_EQ(dataset.frames[2].timestamp, 13.0);
  writeText(dir / "timestamps.txt", "12.5\n12.75\n");
  EXPECT_NE(inputErrorOf([&] { openDataset(dir.string()); }).find("timestamps.txt: 2 timestamps for 3 images"), std::string::npos);
  writeText(dir / "timestamps.txt", "12.5\n12.75\n12.75\n");
  EXPECT_NE(inputErrorOf([&] { openDataset(dir.string()); }).find("timestamps.txt:3: timestamps must increase"), std::string::npos);
  writeText(dir / "timestamps.txt", "12.5\n12.75 1\n13\n");
  EXPECT_NE(inputErrorOf([&] { openDataset(dir.string()); }).find("timestamps.txt:2: expected one timestamp"), std::string::npos);
}

TEST(RunFiles, RelocalizationsCsvSaysWhyEachLocalizationFailedAndWhatCameOfIt) {
  RelocalizationAttempt off_the_map;  // no peak verified: no pose
  off_the_map.frame = 46;
  off_the_map.localization.votes = 5;
  RelocalizationAttempt repeated;
  repeated.frame = 47;
  repeated.localization.status = LocalizationStatus::ambiguous;
  repeated.localization.T_map_robot = Pose2(0.125, -0.5, 0.25);
  repeated.localization.votes = 68;
  repeated.localization.runner_up_votes = 62;
  repeated.localization.inliers = 429;
  repeated.localization.strong_inliers = 191;
  repeated.localization.runner_up_inliers = 396;
  RelocalizationAttempt found = repeated;
  found.frame = 52;
  found.localization.status = LocalizationStatus::localized;
  found.outcome = RelocalizationOutcome::joined;
  EXPECT_EQ(formatRelocalizationsCsv({off_the_map, repeated, found}),
            "frame,status,outcome,x,y,theta,votes,runner_up_votes,inliers,strong_inliers,runner_up_inliers\n"
            "46,too_few_votes,not_localized,,,,5,0,0,0,0\n"
            "47,ambiguous,not_localized,0.125000000,-0.500000000,0.250000000,68,62,429,191,396\n"
            "52,localized,joined,0.125000000,-0.500000000,0.250000000,68,62,429,191,396\n");
  EXPECT_EQ(formatRelocalizationsCsv({}), "frame,status,outcome,x,y,theta,votes,runner_up_votes,inliers,strong_inliers,runner_up_inliers\n");
}
