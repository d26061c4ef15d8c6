#pragma once
// Ctrl-C (SIGINT) and SIGTERM during a run: the first one asks the run to stop after the current frame and
// write what it has; a second one ends the process at once (the default action).

namespace groundslam::apps {

void installStopHandlers();
/// The signal that asked the run to stop, 0 when none did.
int stopSignal();

/// Thrown once an interrupted run has written its partial results; main exits with 128 + signal.
struct Interrupted {
  int signal;
};

}  // namespace groundslam::apps
