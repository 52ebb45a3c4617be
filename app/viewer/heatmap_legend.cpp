// Heat-map ramp, scale positions, legend ticks and the locked maximum.
#include "heatmap_legend.h"

#include <algorithm>
#include <cmath>

#include "count_text.h"

namespace flashgs::viewer {

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

std::vector<LegendTick> legend_ticks(std::uint64_t max_count, bool log_scale) {
  max_count = std::max<std::uint64_t>(1, max_count);
  std::vector<std::uint64_t> values{0};
  if (log_scale) {
    for (std::uint64_t v = 1; v < max_count; v *= 10) values.push_back(v);
  } else {
    // About five steps of 1, 2 or 5 x 10^k.
    const double raw = double(max_count) / 5.0;
    const double decade = std::pow(10.0, std::floor(std::log10(std::max(raw, 1.0))));
    double step = decade;
    for (double m : {1.0, 2.0, 5.0, 10.0})
      if (m * decade >= raw) { step = m * decade; break; }
    for (double v = step; v < double(max_count); v += step) values.push_back(std::uint64_t(v));
  }
  // Two labels centred on their ticks leave a character between them when the ticks lie half
  // their lengths and one character apart.
  const float char_fraction = kLegendCharPoints / kLegendBarPoints;
  const auto clear_of = [&](const LegendTick& a, const LegendTick& b) {
    return std::abs(b.position - a.position) >= char_fraction * (0.5f * float(a.label.size() + b.label.size()) + 1.0f);
  };
  const LegendTick top{max_count, 1.0f, human_count(double(max_count))};
  std::vector<LegendTick> ticks;
  for (std::uint64_t v : values) {
    const LegendTick tick{v, heat_position(double(v), double(max_count), log_scale), human_count(double(v))};
    if (clear_of(tick, top) && (ticks.empty() || clear_of(ticks.back(), tick))) ticks.push_back(tick);
  }
  ticks.push_back(top);
  return ticks;
}

std::string legend_caption(int tile_size, bool log_scale, bool locked) {
  return "pairs per " + std::to_string(tile_size) + "x" + std::to_string(tile_size) + " tile, " +
         (log_scale ? "log" : "linear") + " scale" + (locked ? " (max locked)" : "");
}

std::uint64_t HeatScale::update(std::uint64_t frame_max, bool locked) {
  if (!locked || !m_shown) m_max = std::max<std::uint64_t>(1, frame_max);
  m_shown = true;
  return m_max;
}

}  // namespace flashgs::viewer
