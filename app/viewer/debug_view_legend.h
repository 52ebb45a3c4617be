// The debug views' legend (depth and blended count, flashgs/debug_view.h): captions, ticks and the line the log gets.
#pragma once

#include <string>
#include <vector>

#include "flashgs/debug_view.h"
#include "heatmap_legend.h"

namespace flashgs::viewer {

// The views in the order the V key steps through them, and their names in the panel.
inline constexpr FrameView kFrameViews[] = {FrameView::colour, FrameView::depth, FrameView::blended_count};
const char* frame_view_label(FrameView view);  // "Colour", "Depth", "Blended count"
FrameView next_frame_view(FrameView view);

// "blended depth, scene units" / "Gaussians blended per pixel, log scale".
std::string debug_legend_caption(FrameView view);

// Depth: the near and far ends and up to three round values between them, labelled in scene
// units ("1.25"); count: the heat map's log ticks up to the largest count.
std::vector<LegendTick> debug_legend_ticks(FrameView view, const DebugScale& scale);

// "view depth: blended depth, scene units, near 1.25 far 4.5, ticks 1.25@0% 2@24% ...": one
// log line per change, which the tests read.
std::string debug_legend_line(FrameView view, const DebugScale& scale);

}  // namespace flashgs::viewer
