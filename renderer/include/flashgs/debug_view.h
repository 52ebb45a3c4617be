// The debug views of a frame: its per-pixel blended depth or blended-Gaussian count
// (FrameStats::pixel_depth, pixel_blended) as colour images on the heat map's ramp.
#pragma once

#include <cstdint>
#include <string>

#include "flashgs/image.h"
#include "flashgs/stats.h"

namespace flashgs {

enum class FrameView { colour, depth, blended_count };

// "colour", "depth", "count": the --view names of the CLI and the viewer.
const char* frame_view_name(FrameView view);
// The --view name's view; false when `text` names none.
bool parse_frame_view(const std::string& text, FrameView* view);
// "colour|depth|count", for option help and errors.
inline constexpr const char* kFrameViewChoices = "colour|depth|count";

// What a debug image's colours stand for: the depths at the ramp's ends (scene units) and
// the count at its top (log scale from 0).
struct DebugScale {
  bool any_blended = false;  // some pixel blended a Gaussian (else near = far = 0)
  float near_depth = 0, far_depth = 0;
  std::uint32_t max_blended = 0;
};

// The scale of a frame's planes: the smallest and largest depth of its pixels, its largest count.
DebugScale debug_scale(const FrameStats& stats);

// The view of `stats`' planes (a width x height frame rendered with collect_pixel_planes) as
// an image: depth at ramp position (z - near) / (far - near), `background` where nothing
// blended; count at heat_position(c, max, log). Throws flashgs::Error when the planes are
// missing or of another size, or for FrameView::colour.
Image debug_view_image(FrameView view, const FrameStats& stats, int width, int height, const DebugScale& scale,
                       const float background[3]);

}  // namespace flashgs
