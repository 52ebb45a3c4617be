// Compare mode: the baseline and the current configuration rendered for one view, their difference and their times.
#pragma once

#include <string>

#include "flashgs/camera.h"
#include "flashgs/image.h"
#include "flashgs/options.h"
#include "frame_path.h"

namespace flashgs::viewer {

struct CompareResult {
  bool valid = false;
  bool stale = false;             // the view or options changed since it was computed
  std::string current_label;      // RenderOptions::label() of the current configuration
  int width = 0, height = 0;
  ImageDifference difference;     // current vs baseline (float images)
  double current_ms = 0, baseline_ms = 0;        // backend's total frame time
  double current_wall_ms = 0, baseline_wall_ms = 0;  // wall clock around each render
  std::uint64_t current_kv = 0, baseline_kv = 0;
  std::string error;
};

// Renders `camera` with `current` and with the baseline (same tau, background, SH cap) through
// `path`'s host-memory route and compares them. Never throws: errors land in `error`.
CompareResult run_compare(FramePath& path, const Camera& camera, const RenderOptions& current);

}  // namespace flashgs::viewer
