// Compare mode: two configurations rendered for one view (by default the baseline and the current one), their images, difference and times.
#pragma once

#include <atomic>
#include <functional>
#include <string>
#include <vector>

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
// What the panel lists: "flash without Tight box" rather than the label() token.
std::string compare_choice_title(int choice);
// Whether `backend` draws `choice` differently from flash: a switch the backend ignores
// (compare_choice_options turns off a GPU-only one on the CPU) renders flash itself.
bool compare_choice_offered(int choice, Backend backend);
RenderOptions compare_choice_options(int choice, const RenderOptions& current);

// Empty when `left` and `right` differ; else why there is nothing to compare.
std::string same_configuration_problem(const RenderOptions& left, const RenderOptions& right);
// The same for two choices on `backend`, and a choice it does not offer (compare_choice_offered).
std::string compare_sides_problem(int left, int right, const RenderOptions& current, Backend backend);

// The timing the panel shows: warmed renders of both sides, interleaved round by round so a
// change in the machine's load falls on both alike.
inline constexpr int kCompareRounds = 5;
// Median and range of a set of samples (ms, or per-round ratios).
struct Spread {
  double median = 0, min = 0, max = 0;
  int samples = 0;
};
Spread spread_of(const std::vector<double>& samples);
// The speed-up is within noise when its rounds disagree on which side is faster (the range of
// the per-round ratios holds 1).
bool within_noise(const Spread& speed_up);

struct CompareResult {
  bool valid = false;
  bool stale = false;             // the view or options changed since it was computed
  std::string left_label, right_label;  // RenderOptions::label() of each side
  int width = 0, height = 0;
  Image left_image, right_image;  // the two renders (float, top row first)
  ImageDifference difference;     // right vs left
  Spread left_ms, right_ms;            // backend's total frame time over the timed rounds
  Spread left_wall_ms, right_wall_ms;  // wall clock around each render
  Spread speed_up;                     // per round: left time / right time (backend's times)
  std::uint64_t left_kv = 0, right_kv = 0;
  std::string error;              // a render failed, or both sides are the same configuration

  double pair_reduction() const { return left_kv > 0 ? 1.0 - double(right_kv) / double(left_kv) : 0.0; }
};

// Renders `camera` with `left` and with `right` through `path`'s host-memory route and
// compares them: one untimed render of each side first (a first use of a size allocates,
// caches are cold), then `rounds` timed rounds, each rendering both sides, the order
// alternating between rounds. `progress` (may be empty) hears each render done of the
// 2 * (rounds + 1). Once `cancel` is set (it may be null) the renders stop where the path
// can and `error` is kCompareCancelled. Never throws: errors (and two equal configurations)
// land in `error`.
inline constexpr const char kCompareCancelled[] = "cancelled";
CompareResult run_compare(FramePath& path, const Camera& camera, const RenderOptions& left, const RenderOptions& right,
                          int rounds = kCompareRounds, const std::atomic<bool>* cancel = nullptr,
                          const std::function<void(int done, int total)>& progress = {});
// The figures of a finished comparison in one line: "speed-up 2.29x (2.20-2.35 over 5
// rounds)", with ": within noise" when within_noise.
std::string speed_up_text(const CompareResult& r);

}  // namespace flashgs::viewer
