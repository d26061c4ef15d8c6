#include "StopSignals.hpp"

#include <csignal>

namespace groundslam::apps {
namespace {

volatile std::sig_atomic_t g_stop_signal = 0;

extern "C" void onStopSignal(int signal) {
  g_stop_signal = signal;
  std::signal(signal, SIG_DFL);  // a second one ends the process
}

}  // namespace

void installStopHandlers() {
  struct sigaction action {};
  action.sa_handler = onStopSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

int stopSignal() { return static_cast<int>(g_stop_signal); }

}  // namespace groundslam::apps
