#pragma once
// Figures as text: JSON numbers (null when there is nothing to measure) and figures for people (n/a).
#include <cmath>
#include <cstdio>
#include <string>

namespace groundslam {

/// A JSON number with `decimals` decimals, or null when it is not finite.
inline std::string jsonNumber(double value, int decimals) {
  if (!std::isfinite(value)) return "null";
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, value);
  return text;
}

/// A figure for people: `factor * value` with `decimals` decimals, or "n/a" when it is not a number.
inline std::string textNumber(double value, int decimals, double factor = 1.0) {
  return std::isfinite(value) ? jsonNumber(factor * value, decimals) : "n/a";
}

}  // namespace groundslam
