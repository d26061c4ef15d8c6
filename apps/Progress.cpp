#include "Progress.hpp"

#include <cstdio>

#include <unistd.h>

namespace groundslam::apps {

Progress::Progress(std::string label, int total)
    : label_(std::move(label)), total_(total), enabled_(isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()), last_(start_) {}

void Progress::update(int done) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if ((total_ <= 0 || done < total_) && now - last_ < std::chrono::milliseconds(200)) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double rate = elapsed > 0 ? done / elapsed : 0.0;
  if (total_ <= 0) {  // a stream of unknown length (a video or a camera)
    std::fprintf(stderr, "\r%s: %d frames, %.1f frames/s   ", label_.c_str(), done, rate);
    std::fflush(stderr);
    return;
  }
  const double left = rate > 0 ? (total_ - done) / rate : 0.0;
  std::fprintf(stderr, "\r%s: %d/%d frames, %.1f frames/s, %.0f s left   ", label_.c_str(), done, total_, rate, left);
  std::fflush(stderr);
}

void Progress::finish() {
  if (enabled_) std::fprintf(stderr, "\n");
}

}  // namespace groundslam::apps
