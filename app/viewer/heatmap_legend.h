// The heat map's colour scale: a viridis-like ramp (perceptually uniform, readable with colour-blindness), its legend ticks and caption.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace flashgs::viewer {

// Stops of the ramp, evenly spaced from 0 to 1 (display RGB in [0, 1], interpolated linearly):
// the published viridis colours at 0, 1/8, ..., 1 (matplotlib's, van der Walt and Smith
// 2015). The overlay shader receives this table, so that legend and overlay agree.
inline constexpr int kRampStops = 9;
extern const std::array<std::array<float, 3>, kRampStops> kHeatRamp;

// The ramp's colour at t in [0, 1] (clamped).
std::array<float, 3> heat_colour(float t);

// Where a pair count sits on the scale, 0..1: log(1 + c) / log(1 + max), or c / max.
float heat_position(double count, double max_count, bool log_scale);

// The legend bar is kLegendBarPoints wide and its labels are in ImGui's default font, a
// monospace one of kLegendCharPoints a character; both grow with the UI scale, so the bar holds
// the same labels at any scale.
inline constexpr float kLegendBarPoints = 280.0f;
inline constexpr float kLegendCharPoints = 7.0f;

struct LegendTick {
  std::uint64_t value = 0;
  float position = 0;  // 0..1 along the bar
  std::string label;   // centred under the tick
};

// Ticks at round values: 0, 1, 10, 100, ... (log) or 0 and steps of 1, 2 or 5 x 10^k (linear),
// then the maximum itself. A round tick whose label would come within a character of its
// neighbour's (the maximum's included) is left out.
std::vector<LegendTick> legend_ticks(std::uint64_t max_count, bool log_scale);

// "pairs per 16x16 tile, log scale (max locked)": what the bar measures and how.
std::string legend_caption(int tile_size, bool log_scale, bool locked);

// The scale's top: while the lock is on, the maximum on screen when it was ticked (the frame
// after it may already be another configuration's), else this frame's.
class HeatScale {
 public:
  std::uint64_t update(std::uint64_t frame_max, bool locked);
  std::uint64_t max() const { return m_max; }

 private:
  std::uint64_t m_max = 1;
  bool m_shown = false;  // m_max is a frame's (a lock from the start takes the first frame's)
};

}  // namespace flashgs::viewer
