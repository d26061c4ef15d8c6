// `groundslam simulate OUT`: renders a sequence with exact ground truth in the HD Ground format.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include <opencv2/imgcodecs.hpp>  // IMWRITE_* flags; files are written through the media module

#include "Commands.hpp"
#include "Progress.hpp"
#include "groundslam/io/ImageFile.hpp"
#include "groundslam/io/Media.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/Dataset.hpp"
#include "groundslam/io/Files.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/Tum.hpp"
#include "groundslam/sim/Simulator.hpp"

namespace fs = std::filesystem;

namespace groundslam::apps {
namespace {

struct SimulateOptions {
  std::string out_dir;
  std::string name = "sequence";
  std::string texture_image;
  std::string path_kind = "loop";
  std::string resolution = "320x240";
  std::vector<double> distortion;
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  double turn_deg = sim::PathSettings{}.max_turn_rad * 180.0 / M_PI;
  std::vector<std::string> gaps;  ///< FROM:TO ranges of path frames that are not written (a carried robot)
  std::uint64_t ground_seed = 0;  ///< 0: the ground follows --seed and covers the path only
  double drop_probability = 0.0;  ///< chance per frame that the camera starts dropping frames
  int drop_max = 8;               ///< longest run of dropped frames
  std::string image_format = "png";  ///< png (lossless) | jpg
  int jpeg_quality = 95;
  sim::SimulationSettings settings;
};

/// The path frames a FROM:TO gap leaves out: FROM <= i < TO.
std::pair<int, int> parseGap(const std::string& text) {
  int from = 0, to = 0;
  char colon = 0;
  std::istringstream in(text);
  if (!(in >> from >> colon >> to) || colon != ':' || from < 0 || to <= from) {
    throw InputError("--gap: expected FROM:TO with 0 <= FROM < TO (path frames left out), got '" + text + "'");
  }
  return {from, to};
}

cv::Size parseResolution(const std::string& text) {
  int w = 0, h = 0;
  char x = 0;
  std::istringstream in(text);
  if (!(in >> w >> x >> h) || x != 'x' || w < 16 || h < 16 || w > 8000 || h > 8000) {
    throw InputError("--resolution: expected WIDTHxHEIGHT (e.g. 1600x1200), got '" + text + "'");
  }
  return {w, h};
}

sim::SimulationSettings resolveSettings(SimulateOptions& o) {
  sim::SimulationSettings s = o.settings;
  const cv::Size size = parseResolution(o.resolution);
  s.camera = sim::scaledHdGroundIntrinsics(size.width, size.height);
  if (o.fx > 0) s.camera.fx = o.fx;
  if (o.fy > 0) s.camera.fy = o.fy;
  if (o.cx > 0) s.camera.cx = o.cx;
  if (o.cy > 0) s.camera.cy = o.cy;
  if (!o.distortion.empty()) {
    if (o.distortion.size() != 5) throw InputError("--distortion: expected 5 numbers k1 k2 p1 p2 k3");
    std::copy(o.distortion.begin(), o.distortion.end(), s.camera.distortion.begin());
  }
  if (!sim::parsePathKind(o.path_kind, s.path.kind)) throw InputError("--path: unknown path '" + o.path_kind + "'");
  if (o.ground_seed != 0) s.ground_seed = o.ground_seed;
  s.path.max_turn_rad = o.turn_deg * M_PI / 180.0;
  if (s.path.lane_spacing_m <= 0.0) {
    // Lanes overlap by 40% of the footprint's short side, so the robot revisits ground in the opposite heading.
    s.path.lane_spacing_m = 0.6 * s.mounting_height_m * s.camera.height / s.camera.fy;
  }
  return s;
}

std::string describe(const sim::SimulationSettings& s, const SimulateOptions& o) {
  std::ostringstream out;
  out << "# groundslam simulate: the settings that produced this sequence\n"
      << "texture: " << (o.texture_image.empty() ? s.texture_kind : o.texture_image) << "\n"
      << "user_texture_width_m: " << s.user_texture_width_m << "\n"
      << "path: " << sim::pathKindName(s.path.kind) << "\nframes: " << s.path.frames << "\nstep_m: " << s.path.step_m
      << "\nmax_turn_deg: " << o.turn_deg << "\nlaps: " << s.path.laps << "\nlane_length_m: " << s.path.lane_length_m
      << "\nlane_spacing_m: " << s.path.lane_spacing_m << "\narea_m: " << s.path.area_m
      << "\nresolution: " << s.camera.width << "x" << s.camera.height << "\nmounting_height_m: " << s.mounting_height_m
      << "\nmount_jitter_deg: " << s.mount_jitter_deg << "\nmotion_blur: " << s.motion_blur
      << "\nwet_after: " << s.wet_after << "\nnoise_sigma: " << s.photometry.noise_sigma
      << "\ndefocus_sigma_px: " << s.photometry.defocus_sigma_px
      << "\nexposure_variation: " << s.photometry.exposure_variation << "\nvignetting: " << s.photometry.vignetting
      << "\nheight_jitter_m: " << s.height_jitter_m << "\nshadow: " << s.artifacts.shadow << "\nlens_dirt: " << s.artifacts.lens_dirt
      << "\nglare: " << s.artifacts.glare << "\nbumper: " << s.artifacts.bumper << "\nspin_every: " << s.motion.spin_every << "\nspin_deg: " << s.motion.spin_deg
      << "\ndrop_frames: " << o.drop_probability << "\ndrop_max: " << o.drop_max << "\nimage_format: " << o.image_format
      << "\njpeg_quality: " << o.jpeg_quality
      << "\nseed: " << s.seed << "\npath_seed: " << s.path.seed << "\nground_seed: " << o.ground_seed << "\nground_size_m: " << s.ground_size_m << "\ngaps: [";
  for (size_t i = 0; i < o.gaps.size(); ++i) out << (i ? ", " : "") << "'" << o.gaps[i] << "'";
  out << "]\n";
  return out.str();
}

void simulate(SimulateOptions& o) {
  const sim::SimulationSettings settings = resolveSettings(o);
  cv::Mat user_texture;
  if (!o.texture_image.empty()) {
    user_texture = loadGrayImageAnySize(o.texture_image);
  }
  const sim::SequenceSimulator simulator(settings, user_texture);
  // A folder that holds something other than an earlier simulation is not overwritten.
  std::error_code error;
  if (fs::exists(o.out_dir, error) && !fs::is_empty(o.out_dir, error) && !fs::exists(fs::path(o.out_dir) / "simulation.yaml", error)) {
    throw InputError(o.out_dir + ": the folder exists and holds no earlier simulation; choose a new or empty folder");
  }
  // An earlier simulation's images go: a longer earlier run would leave frames that are not in this list.
  if (fs::exists(fs::path(o.out_dir) / "simulation.yaml", error)) fs::remove_all(fs::path(o.out_dir) / "images", error);
  fs::create_directories(fs::path(o.out_dir) / "images");

  RunSettings camera_file;  // camera.yaml: the camera section, and the dataset section's map scale (default)
  camera_file.config.camera = cameraConfigOf(settings.camera, settings.mounting_height_m);
  const double meters_per_pixel = settings.mounting_height_m / settings.camera.fx;
  std::vector<std::string> images;
  std::vector<Eigen::Matrix3d> homographies;
  std::vector<StampedPose> groundtruth;
  std::vector<std::pair<int, int>> gaps;
  for (const std::string& gap : o.gaps) gaps.push_back(parseGap(gap));
  const std::vector<bool> dropped = sim::droppedFrames(simulator.frameCount(), o.drop_probability, o.drop_max, settings.seed);
  const auto inGap = [&](int i) {
    return dropped[static_cast<size_t>(i)] ||
           std::any_of(gaps.begin(), gaps.end(), [&](const auto& g) { return i >= g.first && i < g.second; });
  };
  std::ostringstream mount_csv;
  mount_csv << "index,path_frame,roll_deg,pitch_deg,height_m\n";
  Progress progress("simulate", simulator.frameCount());
  for (int i = 0; i < simulator.frameCount(); ++i) {
    if (inGap(i)) continue;
    char name[32];
    std::snprintf(name, sizeof(name), "images/%06d.%s", i, o.image_format.c_str());
    const std::string path = (fs::path(o.out_dir) / name).string();
    if (!media().write(path, simulator.renderFrame(i), {cv::IMWRITE_JPEG_QUALITY, o.jpeg_quality})) {
      throw InputError(path + ": cannot write image");
    }
    const Pose2& pose = simulator.groundTruth()[static_cast<size_t>(i)];
    images.push_back(name);
    homographies.push_back(mapHomographyFromRobotPose(pose, settings.camera, meters_per_pixel));
    groundtruth.push_back({static_cast<double>(images.size() - 1), pose});  // timestamps are list indices
    const Eigen::Vector3d mount = simulator.mountStateAt(i);
    char row[160];
    std::snprintf(row, sizeof(row), "%zu,%d,%.6f,%.6f,%.6f\n", images.size() - 1, i, mount.x() * 180.0 / M_PI,
                  mount.y() * 180.0 / M_PI, mount.z());
    mount_csv << row;
    progress.update(i + 1);
  }
  progress.finish();
  writeFileAtomically((fs::path(o.out_dir) / "camera.yaml").string(), configToYaml(camera_file, {"camera", "dataset"}));
  writeTum((fs::path(o.out_dir) / "groundtruth.tum").string(), groundtruth);
  // The frames' times, as groundtruth.tum has them (list indices): a dataset's timestamps.txt wins over
  // numeric file names, which after dropped frames or gaps would skip numbers.
  std::string times;
  for (const StampedPose& pose : groundtruth) times += std::to_string(static_cast<long long>(pose.timestamp)) + "\n";
  writeFileAtomically((fs::path(o.out_dir) / "timestamps.txt").string(), times);
  writeFileAtomically((fs::path(o.out_dir) / "mount.csv").string(), mount_csv.str());
  writeFileAtomically((fs::path(o.out_dir) / "simulation.yaml").string(), describe(settings, o));
  // The list goes last: a sequence without its list is visibly incomplete.
  const std::string list = (fs::path(o.out_dir) / (o.name + ".txt")).string();
  writeFileAtomically(list, formatHdGroundList(images, homographies));
  std::cout << "simulated " << images.size() << " frames (" << (o.texture_image.empty() ? o.settings.texture_kind : o.texture_image) << ", "
            << o.path_kind << ") -> " << list << "\n";
}

}  // namespace

void addSimulateCommand(CLI::App& app) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand("simulate", "Render a ground-texture sequence with exact ground truth (HD Ground format)");
  cmd->add_option("OUT", o->out_dir, "Output folder")->required();
  cmd->add_option("--name", o->name, "Name of the list file (NAME.txt)")->capture_default_str();
  cmd->add_option("--image-format", o->image_format, "Image files: png (lossless) or jpg")
      ->check(CLI::IsMember({"png", "jpg"}))->capture_default_str();
  cmd->add_option("--jpeg-quality", o->jpeg_quality, "JPEG quality with --image-format jpg")
      ->check(CLI::Range(1, 100))->capture_default_str();
  cmd->add_option("--texture-kind", o->settings.texture_kind, "Procedural ground texture")
      ->check(CLI::IsMember(sim::textureKindNames()))->capture_default_str();
  cmd->add_option("--texture", o->texture_image, "Use this image as the ground instead")->check(CLI::ExistingFile);
  cmd->add_option("--texture-width-m", o->settings.user_texture_width_m, "Metric width of --texture")
      ->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--path", o->path_kind, "Path shape")->check(CLI::IsMember(sim::pathKindNames()))->capture_default_str();
  cmd->add_option("--frames", o->settings.path.frames, "Number of frames")->check(CLI::Range(2, 1000000))->capture_default_str();
  cmd->add_option("--step-m", o->settings.path.step_m, "Distance between frames, metres")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--turn-deg", o->turn_deg, "Largest heading change per frame (random walk), degrees")
      ->check(CLI::Range(0.0, 90.0))->capture_default_str();
  cmd->add_option("--laps", o->settings.path.laps, "Loop: times around")->check(CLI::Range(1, 1000))->capture_default_str();
  cmd->add_option("--lane-length-m", o->settings.path.lane_length_m, "Lawnmower: lane length")->check(CLI::PositiveNumber)->capture_default_str();
  o->settings.path.lane_spacing_m = 0.0;  // automatic unless given (the help shows 0)
  cmd->add_option("--lane-spacing-m", o->settings.path.lane_spacing_m, "Lawnmower: lane spacing (0: 60% of the footprint)")
      ->capture_default_str();
  cmd->add_option("--area-m", o->settings.path.area_m, "Random walk: side of the area")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--resolution", o->resolution, "Image size WIDTHxHEIGHT (1600x1200 for HD Ground-like data)")->capture_default_str();
  cmd->add_option("--fx", o->fx, "Focal length x, pixels (default: HD Ground's, scaled)");
  cmd->add_option("--fy", o->fy, "Focal length y, pixels");
  cmd->add_option("--cx", o->cx, "Principal point x, pixels");
  cmd->add_option("--cy", o->cy, "Principal point y, pixels");
  cmd->add_option("--distortion", o->distortion, "OpenCV distortion k1 k2 p1 p2 k3")->expected(5)->delimiter(',');
  cmd->add_option("--height-m", o->settings.mounting_height_m, "Camera mounting height")->check(CLI::PositiveNumber)->capture_default_str();
  cmd->add_option("--jitter-deg", o->settings.mount_jitter_deg, "Roll/pitch jitter of the mount, degrees (std)")
      ->check(CLI::Range(0.0, 20.0))->capture_default_str();
  cmd->add_option("--noise", o->settings.photometry.noise_sigma, "Sensor noise, grey levels (std)")->check(CLI::Range(0.0, 100.0))->capture_default_str();
  cmd->add_option("--defocus-px", o->settings.photometry.defocus_sigma_px, "Defocus blur sigma, pixels")->check(CLI::Range(0.0, 20.0))->capture_default_str();
  cmd->add_option("--motion-blur", o->settings.motion_blur, "Exposure time as a fraction of the frame interval")
      ->check(CLI::Range(0.0, 1.0))->capture_default_str();
  cmd->add_option("--exposure-variation", o->settings.photometry.exposure_variation, "Relative exposure change amplitude")
      ->check(CLI::Range(0.0, 0.9))->capture_default_str();
  cmd->add_option("--vignetting", o->settings.photometry.vignetting, "Darkening at the corners (0-1)")->check(CLI::Range(0.0, 1.0))->capture_default_str();
  cmd->add_option("--wet-after", o->settings.wet_after, "Fraction of the path after which the ground is wet (1: never)")
      ->check(CLI::Range(0.0, 1.0))->capture_default_str();
  cmd->add_option("--seed", o->settings.seed, "Seed of every random choice but the path's (--path-seed)")->capture_default_str();
  cmd->add_option("--path-seed", o->settings.path.seed,
                  "Seed of the random walk's turns (other paths have none); apart from --seed, so that a new --seed keeps "
                  "the path of earlier sequences")
      ->capture_default_str();
  cmd->add_option("--ground-seed", o->ground_seed,
                  "Lay the ground from this seed over a fixed square around the origin: sessions with other paths, seeds and "
                  "looks see the same floor (0: the ground follows --seed)")
      ->capture_default_str();
  cmd->add_option("--ground-size-m", o->settings.ground_size_m, "With --ground-seed: side of the ground square")
      ->check(CLI::Range(0.1, 20.0))->capture_default_str();
  cmd->add_option("--height-jitter-m", o->settings.height_jitter_m, "Camera height jitter, metres (std, smooth over time)")
      ->check(CLI::Range(0.0, 0.05))->capture_default_str();
  cmd->add_option("--shadow", o->settings.artifacts.shadow, "Darkness of the robot's own shadow, 0-1 (its edge turns with the heading)")
      ->check(CLI::Range(0.0, 1.0))->capture_default_str();
  cmd->add_option("--lens-dirt", o->settings.artifacts.lens_dirt, "Dark blotches fixed on the lens")->check(CLI::Range(0, 100))->capture_default_str();
  cmd->add_option("--glare", o->settings.artifacts.glare, "Peak of a bright patch fixed in the image (1 saturates)")
      ->check(CLI::Range(0.0, 5.0))->capture_default_str();
  cmd->add_option("--bumper", o->settings.artifacts.bumper, "Share of the image height hidden by a part of the robot in view")
      ->check(CLI::Range(0.0, 0.5))->capture_default_str();
  cmd->add_option("--spin-every", o->settings.motion.spin_every,
                  "Every N frames the robot turns sharply on the spot by --spin-deg, half a period later back (0: never)")
      ->check(CLI::Range(0, 1000000))->capture_default_str();
  cmd->add_option("--spin-deg", o->settings.motion.spin_deg, "Size of each sharp turn, degrees")->check(CLI::Range(0.0, 180.0))->capture_default_str();
  cmd->add_option("--drop-frames", o->drop_probability, "Chance per frame that the camera drops the next 1 to --drop-max frames")
      ->check(CLI::Range(0.0, 0.5))->capture_default_str();
  cmd->add_option("--drop-max", o->drop_max, "Longest run of dropped frames")->check(CLI::Range(1, 1000))->capture_default_str();
  cmd->add_option("--gap", o->gaps, "FROM:TO: leave out path frames FROM <= i < TO (the robot is carried; repeatable)");
  cmd->callback([o]() { simulate(*o); });
}

}  // namespace groundslam::apps
