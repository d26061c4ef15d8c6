#include "Progress.hpp"

#include <cstdio>

#include <unistd.h>

namespace groundslam::apps {

Progress::Progress(std::string label, int total, std::string unit)
    : label_(std::move(label)), total_(total), unit_(std::move(unit)), enabled_(isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()), last_(start_) {}

void Progress::update(int done) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if ((total_ <= 0 || done < total_) && now - last_ < std::chrono::milliseconds(200)) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double rate = elapsed > 0 ? done / elapsed : 0.0;
  if (total_ <= 0) {  // a stream of unknown length (a video or a camera)
    std::fprintf(stderr, "\r%s: %d %s, %.1f/s   ", label_.c_str(), done, unit_.c_str(), rate);
    std::fflush(stderr);
    return;
  }
  const double left = rate > 0 ? (total_ - done) / rate : 0.0;
  std::fprintf(stderr, "\r%s: %d/%d %s, %.1f %s/s, %.0f s left   ", label_.c_str(), done, total_, unit_.c_str(), rate,
               unit_.c_str(), left);
  std::fflush(stderr);
}

void Progress::finish() {
  if (enabled_) std::fprintf(stderr, "\n");
}

}  // namespace groundslam::apps
