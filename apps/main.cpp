// groundslam: SLAM for robots with a downward-looking camera (Hart et al., ICRA 2023).
#include <exception>
#include <iostream>
#include <string>

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>

#include "Commands.hpp"
#include "StopSignals.hpp"
#include "groundslam/io/InputError.hpp"

int main(int argc, char** argv) {
  CLI::App app{"groundslam: monocular SLAM on ground textures"};
  app.set_version_flag("--version", std::string("groundslam ") + GROUNDSLAM_VERSION);
  app.require_subcommand(1);
  groundslam::apps::addSimulateCommand(app);
  groundslam::apps::addRunCommand(app);
  groundslam::apps::addEvaluateCommand(app);
  groundslam::apps::addVocabularyCommand(app);
  groundslam::apps::addReportCommand(app);
  groundslam::apps::addFloorCommand(app);
  groundslam::apps::addLocalizeCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const groundslam::apps::Interrupted& stop) {
    return 128 + stop.signal;
  } catch (const groundslam::InputError& e) {
    std::cerr << "groundslam: error: " << e.what() << "\n";
    return 2;
  } catch (const cv::Exception& e) {
    std::cerr << "groundslam: error: OpenCV: " << e.what() << "\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "groundslam: error: " << e.what() << "\n";
    return 3;
  }
  return 0;
}
