// The one colour scale of the heat map and the debug views: a viridis-like ramp (perceptually uniform, readable with colour-blindness).
#pragma once

#include <array>

namespace flashgs {

// Stops of the ramp, evenly spaced from 0 to 1 (display RGB in [0, 1], interpolated linearly):
// the published viridis colours at 0, 1/8, ..., 1 (matplotlib's, van der Walt and Smith
// 2015). The viewer's overlay shader receives this table, so that legend and overlay agree.
inline constexpr int kRampStops = 9;
extern const std::array<std::array<float, 3>, kRampStops> kHeatRamp;

// The ramp's colour at t in [0, 1] (clamped; NaN is 0).
std::array<float, 3> heat_colour(float t);

// Where a count sits on the scale, 0..1: log(1 + c) / log(1 + max), or c / max.
float heat_position(double count, double max_count, bool log_scale);

}  // namespace flashgs
