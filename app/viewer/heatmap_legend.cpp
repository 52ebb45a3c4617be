// Heat-map legend ticks and the locked maximum.
#include "heatmap_legend.h"

#include <algorithm>
#include <cmath>

#include "count_text.h"

namespace flashgs::viewer {

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
