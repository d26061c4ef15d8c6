#pragma once
// The turn between two images of the same ground from the magnitudes of their spectra, which a translation leaves
// alone (the first step of Fourier-Mellin registration): where too few keypoints match to fit a motion (a quarter
// turn on the spot, frames dropped, a blurred floor), the turn can still be measured. A spectrum's magnitude is
// symmetric, so the turn is known only up to half a turn; the caller chooses between the two.

#include <opencv2/core.hpp>

namespace groundslam {

struct SpectralTurnSettings {
  double min_frequency = 0.08;   ///< of the sampling rate: below it, the light's slow changes and the window's edge
  double max_frequency = 0.45;   ///< above it, the sensor's noise
  int angle_bins = 360;          ///< over half a turn
  int radius_bins = 40;
  double peak_exclusion_deg = 5.0;  ///< the runner-up turn is sought at least this far from the best one
};

struct SpectralTurn {
  /// `current` is `previous` turned counterclockwise as displayed (x right, y down) by this, or by it plus half a
  /// turn; in (-pi/2, pi/2].
  double turn_rad = 0.0;
  /// How much better the best turn explains the spectra than the best turn peak_exclusion_deg or more away (>= 1;
  /// infinity when no other turn correlates at all; 0 when nothing does).
  double peak_ratio = 0.0;
};

/// `previous` and `current`: single-channel images of one size (any depth), what stays still in the image already
/// taken away by the caller (e.g. the mean of recent images). The central square of each is used.
SpectralTurn spectralTurn(const cv::Mat& previous, const cv::Mat& current, const SpectralTurnSettings& settings = {});

/// How well `current`, its turn undone (turned back by `turn_rad` about its centre, as spectralTurn reports turns),
/// matches `previous` by a translation alone: the peak of their phase correlation over the central squares (0..1).
/// Of spectralTurn's two turns, half a turn apart, the right one's is clearly the higher.
double phasePeakAfterTurn(const cv::Mat& previous, const cv::Mat& current, double turn_rad);

/// The rest of Fourier-Mellin registration: with the turn known, the translation from the phase correlation.
struct TurnAndShift {
  /// A pixel of `current` to where it is seen in `previous` (pixels of these images): the turn undone about the
  /// image centre, then the shift.
  cv::Matx23d W_previous_current = cv::Matx23d::eye();
  double response = 0.0;  ///< the phase correlation's peak (0..1), as phasePeakAfterTurn
};
TurnAndShift shiftAfterTurn(const cv::Mat& previous, const cv::Mat& current, double turn_rad);

}  // namespace groundslam
