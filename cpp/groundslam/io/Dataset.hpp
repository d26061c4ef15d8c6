#pragma once
// Input sequences: an HD Ground list (`NAME.txt` with poses, `NAME.test` without) or a plain folder of
// images in natural sort order. Formats are fixed by docs/conventions.md.

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "groundslam/core/CameraModel.hpp"
#include "groundslam/core/Pose2.hpp"
#include "groundslam/core/Trajectory.hpp"
#include "groundslam/io/ImageFile.hpp"
#include "groundslam/pipeline/Config.hpp"

namespace groundslam {

struct DatasetFrame {
  std::string image_path;                         ///< usable path (list-relative paths resolved)
  double timestamp = 0.0;                         ///< seconds (see Dataset::timestamps_from), else the frame index
  std::optional<Eigen::Matrix3d> map_from_image;  ///< HD Ground's A: image pixel -> map pixel
  bool pose_reliable = true;                      ///< false for a `* ` pose line
};

struct Dataset {
  std::string source;                      ///< the list file or folder that was opened
  std::vector<DatasetFrame> frames;
  std::optional<std::string> camera_yaml;  ///< `camera.yaml` beside the list or in the folder
  /// Where the frames' timestamps come from: a `timestamps.txt` (its path; one time in seconds per image, in
  /// order, beside the list or in the images' folder), "file names" (every image named by a number, e.g.
  /// 1700000000.133.png, increasing), or "index" (0, 1, 2, ...).
  std::string timestamps_from = "index";
  /// A video file or a camera device instead of images (then `frames` is empty): read in order through
  /// OpenCV's VideoCapture, timestamps from the video's clock (a device: seconds since the first frame).
  std::optional<std::string> video_file;
  std::optional<int> camera_device;
  long long video_start = 0, video_stop = -1, video_every = 1;  ///< frames kept (selectFrames), for videos
  bool isVideo() const { return video_file.has_value() || camera_device.has_value(); }
  bool hasGroundTruth() const;
};

/// One image of an HD Ground list as written in the file.
struct HdGroundListEntry {
  std::string image;                              ///< the path as written (relative to the list's folder)
  int line_number = 0;                            ///< the line that names the image
  std::optional<Eigen::Matrix3d> map_from_image;  ///< its pose line's A, in a `.txt` list
  bool pose_reliable = true;                      ///< false for a `*` pose line
};

/// Parses the text of an HD Ground list (`with_poses`: a `.txt` list, image and pose lines alternate).
/// Checks every pose matrix; does not look at the file system. Throws InputError "FILE:LINE: ...".
std::vector<HdGroundListEntry> parseHdGroundList(const std::string& text, const std::string& file, bool with_poses);

/// Opens a list file (HD Ground, or a .txt of image paths), an image folder or a video file (.mp4, .avi,
/// .mkv, .mov, .webm). Throws InputError naming the path (and line).
Dataset openDataset(const std::string& path);

/// A camera device (OpenCV's index, /dev/videoN), with `camera_yaml` for its calibration and mount.
Dataset openCameraDevice(int device, const std::optional<std::string>& camera_yaml);

/// True for file names with a video extension.
bool isVideoFile(const std::string& path);

/// Keeps frames start, start + every, ... before `stop` (negative: to the end); their timestamps stay. Throws
/// InputError when no frame is left or a value is out of range.
void selectFrames(Dataset& dataset, long long start, long long stop, long long every);

/// Robot pose from HD Ground's A (docs/conventions.md): m = A (cx, cy, 1); x = s m_x, y = -s m_y,
/// theta = atan2(-A10, A00), with s metres per map pixel.
Pose2 robotPoseFromMapHomography(const Eigen::Matrix3d& A, double cx, double cy, double meters_per_pixel);

/// The inverse for the default straight-down mount: the A that a robot at T_world_robot sees.
Eigen::Matrix3d mapHomographyFromRobotPose(const Pose2& T_world_robot, const CameraIntrinsics& intrinsics,
                                           double meters_per_pixel);

/// The ground-truth robot poses of the frames whose pose line is reliable, converted as HD Ground's convention
/// says with the camera's principal point and the map scale (empty: mounting_height_m / fx).
Trajectory groundTruthOf(const Dataset& dataset, const CameraConfig& camera, std::optional<double> map_meters_per_pixel);

/// Writes an HD Ground list: image paths (relative to the list's folder) and their A matrices.
std::string formatHdGroundList(const std::vector<std::string>& relative_image_paths,
                               const std::vector<Eigen::Matrix3d>& map_from_image);

}  // namespace groundslam
