// The debug views' names, scales and colour images.
#include "flashgs/debug_view.h"

#include <algorithm>
#include <cmath>

#include "flashgs/colour_ramp.h"
#include "flashgs/error.h"

namespace flashgs {

const char* frame_view_name(FrameView view) {
  switch (view) {
    case FrameView::depth: return "depth";
    case FrameView::blended_count: return "count";
    case FrameView::colour: break;
  }
  return "colour";
}

bool parse_frame_view(const std::string& text, FrameView* view) {
  for (FrameView v : {FrameView::colour, FrameView::depth, FrameView::blended_count})
    if (text == frame_view_name(v)) {
      *view = v;
      return true;
    }
  return false;
}

DebugScale debug_scale(const FrameStats& stats) {
  DebugScale scale;
  for (float z : stats.pixel_depth) {
    if (!std::isfinite(z)) continue;
    if (!scale.any_blended) scale.near_depth = scale.far_depth = z;
    scale.any_blended = true;
    scale.near_depth = std::min(scale.near_depth, z);
    scale.far_depth = std::max(scale.far_depth, z);
  }
  for (std::uint32_t c : stats.pixel_blended) scale.max_blended = std::max(scale.max_blended, c);
  return scale;
}

Image debug_view_image(FrameView view, const FrameStats& stats, int width, int height, const DebugScale& scale,
                       const float background[3]) {
  if (view == FrameView::colour) throw Error("debug view: the colour view has no debug image");
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  if (stats.pixel_depth.size() != pixels || stats.pixel_blended.size() != pixels)
    throw Error("debug view: the frame has no per-pixel planes of " + std::to_string(width) + "x" +
                std::to_string(height) + " (render it with collect_pixel_planes)");
  Image image;
  image.resize(width, height);
  const float span = scale.far_depth - scale.near_depth;
  for (std::size_t i = 0; i < pixels; ++i) {
    float* out = &image.rgb[i * 3];
    if (view == FrameView::depth) {
      const float z = stats.pixel_depth[i];
      if (!std::isfinite(z)) {
        std::copy(background, background + 3, out);
        continue;
      }
      const auto c = heat_colour(span > 0 ? (z - scale.near_depth) / span : 0.0f);
      std::copy(c.begin(), c.end(), out);
    } else {
      const auto c = heat_colour(heat_position(stats.pixel_blended[i], scale.max_blended, true));
      std::copy(c.begin(), c.end(), out);
    }
  }
  return image;
}

}  // namespace flashgs
