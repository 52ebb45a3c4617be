// ViewerSettings: every user-facing choice of the viewer in one plain struct (the UI and the script both edit it), with the range of each value.
#pragma once

#include <cstddef>

#include <string>

#include "flashgs/debug_view.h"
#include "flashgs/lod_cut.h"
#include "flashgs/options.h"

namespace flashgs::viewer {

enum class NavigationMode { fly, orbit };
// What the comparison shows: its numbers only, left | right split at a divider, or the
// magnified difference image.
enum class CompareView { numbers, split, difference };

// The up-axis choices of the View panel and --up: 0 is "auto" (guessed from the cameras).
inline constexpr const char* kUpAxisNames[] = {"auto", "+x", "-x", "+y", "-y", "+z", "-z"};
inline constexpr int kUpAxisCount = 7;
// The most centres the "Gaussian centres" view draws (a dot per Gaussian of a multi-million
// scene would cost more than its frame under llvmpipe).
inline constexpr std::size_t kMaxCentreMarks = 200000;
// The comparison's two configurations by default: baseline | current (compare_mode.h lists them all).
inline constexpr int kCompareCurrent = 0, kCompareBaseline = 1;

// The allowed interval of a numeric setting: the sliders, the command line and
// keep_settings_valid() all use these, so a typed value cannot leave them.
struct ValueRange {
  float min, max;
  // `value` clamped into the range; a NaN or infinite value gives `fallback` (clamped too).
  float clamp(float value, float fallback) const;
  bool contains(float value) const { return value >= min && value <= max; }  // false for NaN
};

inline constexpr ValueRange kFovRange{1.0f, 170.0f};             // horizontal degrees
inline constexpr ValueRange kRenderScaleRange{0.05f, 4.0f};
inline constexpr ValueRange kStreamErrorRange{0.0f, 16.0f};       // pixels
inline constexpr ValueRange kStreamBudgetRange{0.0f, 100.0f};     // millions of Gaussians
inline constexpr ValueRange kMoveSpeedRange{1e-4f, 1e4f};        // scene extents per second
inline constexpr ValueRange kLookSensitivityRange{1e-5f, 1.0f};  // radians per window point
inline constexpr ValueRange kHeatmapOpacityRange{0.1f, 1.0f};
inline constexpr ValueRange kPathSecondsRange{0.1f, 60.0f};      // seconds per camera of the path
inline constexpr ValueRange kTauRange{1e-6f, 0.99f};             // alpha threshold
inline constexpr ValueRange kBackgroundRange{0.0f, 1.0f};        // each colour channel
inline constexpr int kMaxShDegree = 3;

struct ViewerSettings {
  RenderOptions options;            // algorithm, every optimisation, tau, background, SH cap
  NavigationMode mode = NavigationMode::fly;
  float fov_x_degrees = 60.0f;      // horizontal field of view of the viewer camera
  float stream_max_error_px = kDefaultLodMaxErrorPx;  // a streamed LOD set: refine while a cell's error is larger
  float stream_budget_millions = 0.0f;   // a streamed LOD set: Gaussians drawn at most (0: the caps')
  bool lod_overlay = false;              // a streamed LOD set: each Gaussian in its level's colour
  float render_scale = 1.0f;        // render resolution = framebuffer size * scale
  bool adaptive_resolution = true;  // fewer pixels while moving when a full frame takes > 33 ms
  int forced_width = 0, forced_height = 0;  // > 0: render at exactly this size (scripted runs)
  bool flip_up = false;             // invert the world-up axis guessed from the scene
  float move_speed = 1.0f;          // fly speed in scene extents per second (wheel scales it)
  float look_sensitivity = 0.004f;  // radians per window point of mouse motion
  bool heatmap = false;             // per-tile pair-count overlay (tile counts collected only then)
  bool heatmap_log = true;          // log scale for the overlay
  float heatmap_opacity = 0.45f;
  bool vsync = true;
  bool continuous = true;           // re-render every frame (FPS); off: only when something changed
  bool show_ui = true;
  bool show_help = false;           // the shortcut table (F1)
  float path_seconds_per_camera = 2.0f;
  int up_axis = 0;                  // index into kUpAxisNames
  bool show_grid = false;           // ground grid and axes over the image (G)
  bool show_frustums = false;       // the training cameras as frustums, clickable
  bool show_centres = false;        // the Gaussians' centres as dots (a debug view; kMaxCentreMarks)
  FrameView view = FrameView::colour;  // the colour, or the blended depth or count (V)
  bool heatmap_lock_max = false;    // keep the heat map's maximum while switching configurations
  bool screenshot_overlay = false;  // screenshots show the heat map as the window does
  std::string screenshot_folder;    // where F12 saves (timestamped names); empty: working directory
  CompareView compare_view = CompareView::split;
  int compare_left = kCompareBaseline, compare_right = kCompareCurrent;  // compare_mode.h choices
};

// Puts every numeric setting back into its range after the panels edited it: a NaN or
// infinite value (ImGui parses "nan" and "inf" in a Ctrl+click field) takes the value it had
// in `before`, anything else is clamped.
void keep_settings_valid(ViewerSettings& settings, const ViewerSettings& before);

// The one rule for switching between the baseline and flash (the B key, the radio buttons and
// --algorithm): only the algorithm changes. The baseline ignores the optimisation switches, so
// they stay as they were and come back with flash.
void switch_algorithm(RenderOptions& options, Algorithm to);

}  // namespace flashgs::viewer
