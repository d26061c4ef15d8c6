#pragma once
// A one-line progress display on a terminal (frames done, frames/s, time left); silent otherwise.
#include <chrono>
#include <string>

namespace groundslam::apps {

class Progress {
 public:
  /// `unit`: what is counted ("frames", "%", ...).
  Progress(std::string label, int total, std::string unit = "frames");
  void update(int done);
  void finish();

 private:
  std::string label_;
  int total_;
  std::string unit_;
  bool enabled_;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace groundslam::apps
