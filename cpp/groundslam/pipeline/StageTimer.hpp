#pragma once
// Per-stage wall-clock timing of the pipeline (FrameResult::times, PreparedFrame).

#include <chrono>

namespace groundslam {

/// Milliseconds since the last call (or construction).
class StageTimer {
 public:
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - last_).count();
    last_ = now;
    return ms;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

}  // namespace groundslam
