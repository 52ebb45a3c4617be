// Captions and ticks of the depth and blended-count legends.
#include "debug_view_legend.h"

#include <cmath>
#include <cstdio>

namespace flashgs::viewer {

const char* frame_view_label(FrameView view) {
  switch (view) {
    case FrameView::depth: return "Depth";
    case FrameView::blended_count: return "Blended count";
    case FrameView::colour: break;
  }
  return "Colour";
}

FrameView next_frame_view(FrameView view) {
  constexpr int count = int(sizeof kFrameViews / sizeof kFrameViews[0]);
  for (int i = 0; i < count; ++i)
    if (kFrameViews[i] == view) return kFrameViews[(i + 1) % count];
  return FrameView::colour;
}

std::string debug_legend_caption(FrameView view) {
  return view == FrameView::depth ? "blended depth, scene units" : "Gaussians blended per pixel, log scale";
}

namespace {

std::string depth_label(double z) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", z);
  return text;
}

}  // namespace

std::vector<LegendTick> debug_legend_ticks(FrameView view, const DebugScale& scale) {
  if (view == FrameView::blended_count) return legend_ticks(scale.max_blended, true);
  if (!scale.any_blended) return {};
  const double near_z = scale.near_depth, far_z = scale.far_depth, span = far_z - near_z;
  std::vector<LegendTick> ticks{{0, 0.0f, depth_label(near_z)}};
  if (span > 0) {
    // Round values (1, 2 or 5 x 10^k apart, about four steps) strictly between the ends,
    // each clear of its neighbours by its label's width.
    const double raw = span / 4.0, decade = std::pow(10.0, std::floor(std::log10(raw)));
    double step = decade;
    for (double m : {1.0, 2.0, 5.0, 10.0})
      if (m * decade >= raw) {
        step = m * decade;
        break;
      }
    const float char_fraction = kLegendCharPoints / kLegendBarPoints;
    const LegendTick far_tick{0, 1.0f, depth_label(far_z)};
    auto clear_of = [&](const LegendTick& a, const LegendTick& b) {
      return std::abs(b.position - a.position) >= char_fraction * (0.5f * float(a.label.size() + b.label.size()) + 1.0f);
    };
    for (double z = std::ceil(near_z / step) * step; z < far_z; z += step) {
      const LegendTick tick{0, float((z - near_z) / span), depth_label(z)};
      if (tick.position > 0.0f && clear_of(ticks.back(), tick) && clear_of(tick, far_tick)) ticks.push_back(tick);
    }
    ticks.push_back(far_tick);
  }
  return ticks;
}

std::string debug_legend_line(FrameView view, const DebugScale& scale) {
  std::string line = std::string("view ") + frame_view_name(view) + ": " + debug_legend_caption(view);
  char text[96];
  if (view == FrameView::depth) {
    if (!scale.any_blended) return line + ", nothing blended";
    std::snprintf(text, sizeof text, ", near %.6g far %.6g", scale.near_depth, scale.far_depth);
  } else {
    std::snprintf(text, sizeof text, ", max %u", scale.max_blended);
  }
  line += text;
  line += ", ticks";
  for (const LegendTick& t : debug_legend_ticks(view, scale))
    line += " " + t.label + "@" + std::to_string(int(std::lround(t.position * 100.0f))) + "%";
  return line;
}

}  // namespace flashgs::viewer
