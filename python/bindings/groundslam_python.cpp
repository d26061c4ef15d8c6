// Python bindings (pybind11): `import groundslam`. The same library as the `groundslam` program: configuration,
// the SLAM pipeline one image at a time, maps and global localization, image loading and the simulator.
#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "groundslam/groundslam.hpp"
#include "groundslam/localization/GlobalLocalizer.hpp"
#include "groundslam/sim/Texture.hpp"

namespace py = pybind11;
using namespace groundslam;

namespace {

using GrayArray = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>;

/// A 2-D uint8 array as an OpenCV image sharing its memory (valid while the array lives).
cv::Mat asImage(const GrayArray& image) {
  if (image.ndim() != 2) throw std::invalid_argument("image: a 2-D uint8 array (grey) is expected, got " + std::to_string(image.ndim()) + " dimensions");
  return cv::Mat(static_cast<int>(image.shape(0)), static_cast<int>(image.shape(1)), CV_8U,
                 const_cast<std::uint8_t*>(image.data()), static_cast<size_t>(image.strides(0)));
}

py::array_t<std::uint8_t> asArray(const cv::Mat& image) {
  py::array_t<std::uint8_t> out({image.rows, image.cols});
  for (int row = 0; row < image.rows; ++row) std::memcpy(out.mutable_data(row, 0), image.ptr(row), static_cast<size_t>(image.cols));
  return out;
}

/// N x 4 (timestamp, x, y, theta).
py::array_t<double> trajectoryArray(const Trajectory& trajectory) {
  py::array_t<double> out({static_cast<py::ssize_t>(trajectory.size()), py::ssize_t{4}});
  auto a = out.mutable_unchecked<2>();
  for (size_t i = 0; i < trajectory.size(); ++i) {
    const auto r = static_cast<py::ssize_t>(i);
    a(r, 0) = trajectory[i].timestamp;
    a(r, 1) = trajectory[i].T_world_robot.x;
    a(r, 2) = trajectory[i].T_world_robot.y;
    a(r, 3) = trajectory[i].T_world_robot.theta;
  }
  return out;
}

std::shared_ptr<const Vocabulary> vocabularyFor(const RunSettings& settings) {
  if (!settings.config.loop_closure.enabled) return nullptr;
  return std::make_shared<const Vocabulary>(readVocabulary(vocabularyPath(settings.inputs)));
}

/// The simulator with the settings it was built from.
struct PySimulator {
  explicit PySimulator(const sim::SimulationSettings& s) : settings(s), simulator(s) {}
  sim::SimulationSettings settings;
  sim::SequenceSimulator simulator;
};

/// The image must have the configured camera's size: another size would be projected with the wrong intrinsics.
void checkSize(const GrayArray& image, const Config& config) {
  if (image.ndim() == 2 && (image.shape(0) != config.camera.image_height || image.shape(1) != config.camera.image_width)) {
    throw InputError("image is " + std::to_string(image.shape(1)) + "x" + std::to_string(image.shape(0)) +
                     ", the camera configuration says " + std::to_string(config.camera.image_width) + "x" +
                     std::to_string(config.camera.image_height));
  }
}

/// Slam with the vocabulary it was built with (maps are read with it). One call at a time: the GIL is released
/// while an image is processed, so the object's own lock keeps other Python threads out.
struct PySlam {
  explicit PySlam(const RunSettings& s) : config(s.config), vocabulary(vocabularyFor(s)), slam(s.config, vocabulary) {}
  Config config;
  std::shared_ptr<const Vocabulary> vocabulary;
  Slam slam;
  std::mutex lock;
};

/// PipelinedSlam over a Python Slam (kept alive by it): the next image prepared on another thread while the
/// previous one goes through the back end.
struct PyPipelined {
  explicit PyPipelined(PySlam& s) : owner(s), pipelined(s.slam) {}
  PySlam& owner;
  PipelinedSlam pipelined;
};

/// A saved map with what localizing an image on it needs.
struct PyMap {
  PyMap(const std::string& path, const RunSettings& s)
      : config(s.config), vocabulary(vocabularyFor(s)), map(readMap(path, requireVocabulary(vocabulary))), preparer(s.config) {}
  static std::shared_ptr<const Vocabulary> requireVocabulary(std::shared_ptr<const Vocabulary> v) {
    if (!v) throw std::invalid_argument("Map: needs loop closure on in the configuration (its vocabulary reads the map)");
    return v;
  }
  Config config;
  std::shared_ptr<const Vocabulary> vocabulary;
  FeatureMap map;
  FramePreparer preparer;
  mutable std::mutex lock;  ///< one image at a time (the preparer's ORB object)
};

}  // namespace

PYBIND11_MODULE(groundslam, m) {
  m.doc() = "groundslam: monocular SLAM on ground textures (a downward-looking camera)";
  m.attr("__version__") = GROUNDSLAM_VERSION;
  py::register_exception<InputError>(m, "InputError", PyExc_ValueError);

  py::class_<Pose2>(m, "Pose2", "SE(2) pose: x, y in metres, theta in radians")
      .def(py::init<double, double, double>(), py::arg("x") = 0.0, py::arg("y") = 0.0, py::arg("theta") = 0.0)
      .def_readwrite("x", &Pose2::x)
      .def_readwrite("y", &Pose2::y)
      .def_readwrite("theta", &Pose2::theta)
      .def("__repr__", [](const Pose2& p) {
        return "Pose2(x=" + std::to_string(p.x) + ", y=" + std::to_string(p.y) + ", theta=" + std::to_string(p.theta) + ")";
      });

  py::class_<CameraConfig>(m, "CameraConfig", "Intrinsics (pixels), OpenCV distortion k1 k2 p1 p2 k3 and the mount")
      .def(py::init<>())
      .def_readwrite("image_width", &CameraConfig::image_width)
      .def_readwrite("image_height", &CameraConfig::image_height)
      .def_readwrite("fx", &CameraConfig::fx)
      .def_readwrite("fy", &CameraConfig::fy)
      .def_readwrite("cx", &CameraConfig::cx)
      .def_readwrite("cy", &CameraConfig::cy)
      .def_readwrite("distortion", &CameraConfig::distortion)
      .def_property(
          "distortion_model", [](const CameraConfig& c) { return nameOf(c.distortion_model); },
          [](CameraConfig& c, const std::string& name) {
            const auto model = valueNamed<DistortionModel>(name);
            if (!model) throw std::invalid_argument("distortion_model: '" + name + "' is not one of: " + allowedNames<DistortionModel>());
            c.distortion_model = *model;
          },
          "radtan (k1 k2 p1 p2 k3) | equidistant (fisheye: k1 k2 k3 k4 0)")
      .def_readwrite("mounting_height_m", &CameraConfig::mounting_height_m)
      .def_readwrite("T_robot_camera", &CameraConfig::T_robot_camera);

  // Python's Config is what a configuration file sets: the pipeline's settings and the vocabulary's path.
  py::class_<RunSettings>(m, "Config", "Every setting of the pipeline (the defaults of config/default.yaml)")
      .def(py::init<>())
      .def_static("from_yaml", [](const std::string& path) { return loadConfig({path}); }, py::arg("path"),
                  "Reads a configuration YAML (e.g. a dataset's camera.yaml, or one with every section)")
      .def_property(
          "camera",  // a reference: `config.camera.fx = ...` changes this configuration
          py::cpp_function([](RunSettings& s) -> CameraConfig& { return s.config.camera; }, py::return_value_policy::reference_internal),
          [](RunSettings& s, const CameraConfig& camera) { s.config.camera = camera; })
      .def_property(
          "loop_closure_enabled", [](const RunSettings& s) { return s.config.loop_closure.enabled; },
          [](RunSettings& s, bool on) { s.config.loop_closure.enabled = on; })
      .def_property(
          "vocabulary", [](const RunSettings& s) { return s.inputs.vocabulary; },
          [](RunSettings& s, const std::string& path) { s.inputs.vocabulary = path; }, "vocabulary file; empty: the shipped one")
      .def("validate", [](const RunSettings& s) { validateConfig(s.config); },
           "Raises ValueError naming the key when a value cannot be used")
      .def("to_yaml", [](const RunSettings& s) { return configToYaml(s); });

  py::class_<FrameResult>(m, "FrameResult", "What the pipeline reports for one frame")
      .def_readonly("index", &FrameResult::index)
      .def_readonly("timestamp", &FrameResult::timestamp)
      .def_property_readonly("status", &FrameResult::statusName, "first | ok | low_overlap | aligned | unconfirmed | uncertain | sharp_turn | gap (measured, less certain) | fallback_<reason> | lost_<reason> (the frame that lost tracking) | lost | relocalized")
      .def_readonly("pose", &FrameResult::T_world_robot, "the estimate when the frame was processed")
      .def_readonly("keypoints", &FrameResult::keypoints)
      .def_readonly("matches", &FrameResult::matches)
      .def_readonly("inliers", &FrameResult::inliers)
      .def_readonly("loop_closures", &FrameResult::loop_closures)
      .def("__repr__", [](const FrameResult& r) { return "FrameResult(index=" + std::to_string(r.index) + ", status='" + r.statusName() + "')"; });

  py::class_<PySlam>(m, "Slam", "The SLAM pipeline, one image at a time")
      .def(py::init<const RunSettings&>(), py::arg("config"))
      .def(
          "process",
          [](PySlam& s, const GrayArray& image, double timestamp) {
            const cv::Mat view = asImage(image);
            checkSize(image, s.config);
            py::gil_scoped_release release;
            const std::lock_guard<std::mutex> guard(s.lock);
            return s.slam.process(view, timestamp);
          },
          py::arg("image"), py::arg("timestamp"), "image: 2-D uint8 numpy array (the camera's size); returns a FrameResult")
      .def("finish", [](PySlam& s) {
        const std::lock_guard<std::mutex> guard(s.lock);
        s.slam.finish();
      }, "Optimises the whole graph and solves the camera tilt over the whole run; call after the last image")
      .def("trajectory", [](PySlam& s) {
        const std::lock_guard<std::mutex> guard(s.lock);
        return trajectoryArray(s.slam.trajectory());
      },
           "N x 4 float64 array: timestamp, x, y, theta (metres, radians)")
      .def("tum", [](PySlam& s) {
        const std::lock_guard<std::mutex> guard(s.lock);
        return formatTum(s.slam.trajectory());
      }, "The trajectory as TUM lines")
      .def(
          "save_map",
          [](PySlam& s, const std::string& path) {
            const std::lock_guard<std::mutex> guard(s.lock);
            if (!s.slam.featureMap()) throw std::invalid_argument("save_map: needs loop closure (config.loop_closure_enabled)");
            writeMap(path, *s.slam.featureMap(), s.slam.mapSegment());
          },
          py::arg("path"))
      .def(
          "use_map",
          [](PySlam& s, const std::string& path) {
            const std::lock_guard<std::mutex> guard(s.lock);
            if (!s.vocabulary) throw std::invalid_argument("use_map: needs loop closure (config.loop_closure_enabled)");
            s.slam.usePriorMap(readMap(path, s.vocabulary));
          },
          py::arg("path"),
          "Before the first image: start on a map saved earlier (poses come out in its frame)");

  py::class_<PyPipelined>(m, "PipelinedSlam",
                          "A Slam fed one image at a time, the next image's features extracted on another thread while the "
                          "previous one is processed: results come one frame late, identical to Slam.process")
      .def(py::init<PySlam&>(), py::arg("slam"), py::keep_alive<1, 2>())
      .def(
          "push",
          [](PyPipelined& p, const GrayArray& image, double timestamp) {
            const cv::Mat view = asImage(image);
            checkSize(image, p.owner.config);
            py::gil_scoped_release release;
            const std::lock_guard<std::mutex> guard(p.owner.lock);
            return p.pipelined.push(view, timestamp);  // copies the image before returning
          },
          py::arg("image"), py::arg("timestamp"), "The previous image's FrameResult, or None for the first image")
      .def("finish", [](PyPipelined& p) {
        py::gil_scoped_release release;
        const std::lock_guard<std::mutex> guard(p.owner.lock);
        return p.pipelined.finish();
      }, "The last image's FrameResult (None if none is pending); then the whole graph is optimised");

  py::class_<DatasetFrame>(m, "DatasetFrame", "One image of a dataset")
      .def_readonly("image_path", &DatasetFrame::image_path)
      .def_readonly("timestamp", &DatasetFrame::timestamp);
  py::class_<Dataset>(m, "Dataset", "An HD Ground list or a folder of images")
      .def_readonly("source", &Dataset::source)
      .def_readonly("frames", &Dataset::frames)
      .def_readonly("camera_yaml", &Dataset::camera_yaml, "camera.yaml beside the list or in the folder, or None");
  m.def("open_dataset", &openDataset, py::arg("path"), "Opens an HD Ground list (NAME.txt / NAME.test) or an image folder");
  m.def(
      "dataset_config",
      [](const Dataset& dataset, const std::string& config) { return loadDatasetConfig(dataset.camera_yaml, config); },
      py::arg("dataset"), py::arg("config") = "", "The dataset's camera.yaml with an optional configuration file over it");

  py::class_<Localization>(m, "Localization", "One image localized on a map, with no pose prior")
      .def_property_readonly("status", [](const Localization& l) { return std::string(localizationStatusName(l.status)); },
                             "localized | too_few_votes | ambiguous | too_few_inliers | covariance | clustered")
      .def_property_readonly("ok", &Localization::ok)
      .def_readonly("pose", &Localization::T_map_robot, "the robot's pose in the map's frame (when ok)")
      .def_readonly("inliers", &Localization::inliers)
      .def_readonly("votes", &Localization::votes);
  py::class_<PyMap>(m, "Map", "A map written by a run (map.gsmap): images are localized on it one by one")
      .def(py::init<const std::string&, const RunSettings&>(), py::arg("path"), py::arg("config"))
      .def(
          "localize",
          [](const PyMap& map, const GrayArray& image) {
            const cv::Mat view = asImage(image);
            checkSize(image, map.config);
            py::gil_scoped_release release;
            const std::lock_guard<std::mutex> guard(map.lock);
            const PreparedFrame prepared = map.preparer.prepare(view, 0.0);
            return localizeGlobally(map.map, prepared.features, map.config.localization, map.config.odometry);
          },
          py::arg("image"), "Localizes one image (2-D uint8 array) on the map: a Localization")
      .def_property_readonly("keyframes", [](const PyMap& map) { return map.map.anchors().size(); });

  m.def("default_vocabulary", &defaultVocabularyPath, "The shipped vocabulary's path (see GROUNDSLAM_DATA_DIR)");
  m.def("default_config", &defaultConfigPath, "The shipped default.yaml: every key, its default and what it does");
  m.def("defaults_found", [] { return std::filesystem::is_regular_file(defaultVocabularyPath()); },
        "True when the shipped vocabulary is found");
  m.def(
      "load_image",
      [](const std::string& path, int width, int height) { return asArray(loadGrayImage(path, width, height)); },
      py::arg("path"), py::arg("width"), py::arg("height"), "An image file as the 2-D uint8 array groundslam uses");

  py::class_<PySimulator>(m, "Simulator", "Simulated ground-texture sequences with exact ground truth")
      .def(py::init([](const std::string& texture, const std::string& path, int frames, std::uint64_t seed, int width, int height) {
             sim::SimulationSettings settings;
             sim::TextureKind kind;
             if (!sim::parseTextureKind(texture, kind)) {
               throw std::invalid_argument("texture: asphalt | concrete | carpet | tiles");
             }
             settings.texture_kind = texture;
             if (!sim::parsePathKind(path, settings.path.kind)) throw std::invalid_argument("path: loop | lawnmower | random_walk");
             settings.path.frames = frames;
             settings.seed = seed;
             settings.camera = sim::scaledHdGroundIntrinsics(width, height);
             return std::make_unique<PySimulator>(settings);
           }),
           py::arg("texture") = "asphalt", py::arg("path") = "loop", py::arg("frames") = 100, py::arg("seed") = 1,
           py::arg("width") = 320, py::arg("height") = 240)
      .def_property_readonly("frame_count", [](const PySimulator& s) { return s.simulator.frameCount(); })
      .def("render", [](const PySimulator& s, int i) {
        if (i < 0 || i >= s.simulator.frameCount()) throw py::index_error("frame index out of range");
        return asArray(s.simulator.renderFrame(i));
      }, py::arg("index"), "Frame `index` as a 2-D uint8 array")
      .def("ground_truth", [](const PySimulator& s) {
        Trajectory truth;
        for (size_t i = 0; i < s.simulator.groundTruth().size(); ++i) truth.push_back({static_cast<double>(i), s.simulator.groundTruth()[i], true});
        return trajectoryArray(truth);
      }, "N x 4: index, x, y, theta")
      .def("config", [](const PySimulator& s) {
        RunSettings config;
        config.config.camera = cameraConfigOf(s.settings.camera, s.settings.mounting_height_m);
        return config;
      }, "A Config whose camera is the simulated one");
}
