// The heat map's colour scale (flashgs/colour_ramp.h): its legend ticks and caption.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "flashgs/colour_ramp.h"

namespace flashgs::viewer {

// The ramp lives in the renderer library (the CLI's debug images use it too).
using ::flashgs::heat_colour;
using ::flashgs::heat_position;
using ::flashgs::kHeatRamp;
using ::flashgs::kRampStops;

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
