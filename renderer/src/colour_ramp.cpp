// The viridis ramp's stops, its interpolation and a count's place on it.
#include "flashgs/colour_ramp.h"

#include <algorithm>
#include <cmath>

namespace flashgs {

// viridis at t = 0, 0.125, ..., 1: #440154 #472d7b #3b528b #2c728e #21908c
// #27ad81 #5dc863 #aadc32 #fde725 (as R's viridisLite lists them), bytes / 255.
const std::array<std::array<float, 3>, kRampStops> kHeatRamp = {{
    {0x44 / 255.0f, 0x01 / 255.0f, 0x54 / 255.0f},
    {0x47 / 255.0f, 0x2d / 255.0f, 0x7b / 255.0f},
    {0x3b / 255.0f, 0x52 / 255.0f, 0x8b / 255.0f},
    {0x2c / 255.0f, 0x72 / 255.0f, 0x8e / 255.0f},
    {0x21 / 255.0f, 0x90 / 255.0f, 0x8c / 255.0f},
    {0x27 / 255.0f, 0xad / 255.0f, 0x81 / 255.0f},
    {0x5d / 255.0f, 0xc8 / 255.0f, 0x63 / 255.0f},
    {0xaa / 255.0f, 0xdc / 255.0f, 0x32 / 255.0f},
    {0xfd / 255.0f, 0xe7 / 255.0f, 0x25 / 255.0f},
}};

std::array<float, 3> heat_colour(float t) {
  const float s = std::clamp(std::isfinite(t) ? t : 0.0f, 0.0f, 1.0f) * (kRampStops - 1);
  const int i = std::min(int(s), kRampStops - 2);
  const float f = s - float(i);
  std::array<float, 3> c;
  for (int k = 0; k < 3; ++k) c[k] = kHeatRamp[i][k] + (kHeatRamp[i + 1][k] - kHeatRamp[i][k]) * f;
  return c;
}

float heat_position(double count, double max_count, bool log_scale) {
  max_count = std::max(1.0, max_count);
  count = std::clamp(count, 0.0, max_count);
  return float(log_scale ? std::log1p(count) / std::log1p(max_count) : count / max_count);
}

}  // namespace flashgs
