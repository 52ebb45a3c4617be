// Compare mode: two configurations rendered for one view (by default the baseline and the current one), their images, difference and times.
#pragma once

#include <atomic>
#include <string>

#include "flashgs/camera.h"
#include "flashgs/image.h"
#include "flashgs/options.h"
#include "frame_path.h"
#include "viewer_settings.h"

namespace flashgs::viewer {

// The configurations either side of a comparison can be: 0 the current settings, 1 the
// baseline, 2 flash with every optimisation, then flash without one switch of
// kRenderSwitches each. All take tau, background and SH cap from the current settings, so a
// difference is the algorithm's alone.
int compare_choice_count();
std::string compare_choice_name(int choice);  // "current", "baseline", "flash", "flash-no_tight_bbox", ...
int compare_choice_from_name(const std::string& name);  // -1 when unknown
RenderOptions compare_choice_options(int choice, const RenderOptions& current);

// Empty when `left` and `right` differ; else why there is nothing to compare.
std::string same_configuration_problem(const RenderOptions& left, const RenderOptions& right);

struct CompareResult {
  bool valid = false;
  bool stale = false;             // the view or options changed since it was computed
  std::string left_label, right_label;  // RenderOptions::label() of each side
  int width = 0, height = 0;
  Image left_image, right_image;  // the two renders (float, top row first)
  ImageDifference difference;     // right vs left
  double left_ms = 0, right_ms = 0;            // backend's total frame time
  double left_wall_ms = 0, right_wall_ms = 0;  // wall clock around each render
  std::uint64_t left_kv = 0, right_kv = 0;
  std::string error;              // a render failed, or both sides are the same configuration

  double speed_up() const { return right_ms > 0 ? left_ms / right_ms : 0.0; }           // left time / right time
  double pair_reduction() const { return left_kv > 0 ? 1.0 - double(right_kv) / double(left_kv) : 0.0; }
};

// Renders `camera` with `left` and with `right` through `path`'s host-memory route and
// compares them. With `warm_up` each is rendered twice and the second timed (a GPU path's
// first use of a size allocates); the CPU path's buffers are already sized by the frame
// just shown, and a second render would double the wait. Once `cancel` is set (it may be
// null) the renders stop where the path can and `error` is kCompareCancelled. Never throws:
// errors (and two equal configurations) land in `error`.
inline constexpr const char kCompareCancelled[] = "cancelled";
CompareResult run_compare(FramePath& path, const Camera& camera, const RenderOptions& left, const RenderOptions& right,
                          bool warm_up, const std::atomic<bool>* cancel = nullptr);

}  // namespace flashgs::viewer
