#pragma once
// The look of the texture matrix's outdoor condition, for tests that simulate it.
#include "groundslam/sim/Simulator.hpp"

namespace groundslam::testing {

/// A shadow turning with the heading, lens dirt, glare, a bumper, a rocking (0.5 degrees) and bouncing (2 mm) mount,
/// motion and defocus blur, noise, exposure changes, vignetting, wet from 60% of the path.
inline void putUnderTheOutdoorLook(sim::SimulationSettings& s) {
  s.mount_jitter_deg = 0.5;
  s.height_jitter_m = 0.002;
  s.motion_blur = 0.3;
  s.wet_after = 0.6;
  s.photometry = {2.0, 0.6, 0.15, 0.2};
  s.artifacts = {0.6, 6, 0.8, 0.15};
}

}  // namespace groundslam::testing
