// The viewer's ImGui panels: what they show (UiModel), what they change (ViewerSettings) and what they ask for (UiActions).
#pragma once

#include <string>
#include <vector>

#include "compare_mode.h"
#include "debug_view_legend.h"
#include "heatmap_legend.h"
#include "path_editor.h"
#include "flashgs/stats.h"
#include "stats_history.h"
#include "viewer_settings.h"

namespace flashgs::viewer {

// A background load's progress as the panels show it (totals of 0: not known yet).
struct LoadView {
  std::uint64_t bytes_done = 0, bytes_total = 0;
  std::uint64_t gaussians_done = 0, gaussians_total = 0;
  double elapsed_s = 0;
};

struct UiModel {
  std::string frame_path;         // the active presentation path
  std::string frame_path_note;    // why a faster path is not used, if so
  Backend backend = Backend::cpu;  // the renderer behind the frame path (greys the switches it ignores)
  std::string scene_path;
  std::size_t gaussians = 0;
  int sh_degree = 0;
  SplatKernel trained;            // the kernel the scene file names (classic when none)...
  std::string trained_kernel;     // ...and where that came from (kernel_summary)
  const std::vector<std::size_t>* lod_gaussians = nullptr;  // a SOG LOD set's levels, else null
  int lod_level = -1;
  std::string stream_summary;  // a LOD set streamed by view: what is drawn and in memory; empty otherwise
  std::vector<std::uint64_t> stream_levels;            // ...the Gaussians drawn at each level
  const std::vector<float>* stream_read_rates = nullptr;  // ...bytes read per second, oldest first
  int camera_count = 0;
  std::string scene_note;         // loader report / cameras problem
  std::string load_error;         // the last failed load and what is shown instead, one sentence
  std::string loading;            // the file being loaded in the background, if any
  LoadView load;                  // its progress
  const std::vector<std::string>* recent = nullptr;  // recently opened scenes, newest first
  int current_camera = -1;        // the scene camera the view sits on, -1 when moved
  std::string view_description;   // CameraController::view_description
  bool playing = false;
  int render_width = 0, render_height = 0;
  double fps = 0;                 // finished frames per second over the last second (0: idle)
  double last_frame_ms = 0;       // wall time of the last finished frame
  bool rendering = false;         // a frame (or comparison) is being rendered in the background
  const FrameStats* stats = nullptr;
  const StatsHistory* history = nullptr;
  const CompareResult* compare = nullptr;
  std::string comparing;          // the comparison running now ("flash vs baseline at WxH"), if any
  double compare_elapsed_s = 0;   // for how long it has run
  int compare_renders_done = 0, compare_renders_total = 0;  // and how far it is
  std::uint32_t heatmap_max = 0;  // the scale's top (locked or this frame's)
  int tile_size = 16;
  bool compare_shown = false;     // the split or difference image is on screen
  float divider = 0.5f;           // the split's divider, fraction of the width
  float difference_factor = 1.0f;
  std::string compare_problem;    // why the chosen sides cannot be compared (same configuration)
  int export_done = 0, export_total = 0;  // path export progress (total 0: none running)
  std::string dialog_tool;        // the desktop file dialog in use ("zenity"), empty: in-app browser
  bool dialog_open = false;
  float legend_rect_points[4] = {0, 0, 0, 0};  // where the legend bar is drawn, window points
  FrameView debug_shown = FrameView::colour;   // the debug view on screen (colour: none)...
  DebugScale debug_scale;                      // ...and its scale
  float ui_scale = 1.0f;          // widget size multiplier (high-DPI screens)
  std::string status;             // last screenshot / action message
  float world_up[3] = {0, -1, 0};
  float position[3] = {0, 0, 0};
};

struct UiActions {
  std::string open_path;          // non-empty: load this scene
  bool path_entered = false;      // ...sent with Enter from the path field, where the typing goes on
  int lod_level = -1;             // >= 0: load this level of the current SOG LOD set
  bool cancel_load = false;       // stop waiting for the scene being loaded
  int snap_camera = -1;           // >= 0: go to this camera
  bool next_camera = false, previous_camera = false;
  bool toggle_play = false;
  bool flip_up = false;
  bool reset_view = false;
  bool compare = false;
  bool frame_scene = false;       // F: look at the whole scene
  bool up_changed = false;        // the up-axis choice changed
  bool open_dialog = false;       // the file dialog (desktop or in-app)
  std::string export_folder;      // non-empty: export the camera path into this folder
  bool cancel_export = false;
  bool screenshot = false;        // save the rendered image under a timestamped name in the folder
  // The keyframed camera path (PathEditor): what needs the view or the files.
  bool add_key = false;           // I: the view as a new key
  bool replace_key = false;       // the selected key takes the view
  bool delete_key = false;
  int select_key = -1;            // >= 0: select this key and show its view
  bool save_keys = false, load_keys = false;  // to / from the path file field
  bool toggle_preview = false;
  std::string render_keys_folder; // non-empty: render the keyed path's frames into this folder
};

// The text fields of the camera-path section, kept between frames.
struct PathFields {
  std::string file;    // the path file
  std::string folder;  // where its frames are rendered
};

// Draws every panel for this frame (the caller puts typed values back in range afterwards:
// keep_settings_valid). `path_buffer` and `export_buffer` hold the text fields' contents
// between frames.
// `keys` is the authored camera path: its timing, easing and render settings are edited in place.
void draw_panels(const UiModel& model, ViewerSettings& settings, UiActions& actions, std::string& path_buffer,
                 std::string& export_buffer, PathEditor& keys, PathFields& key_fields);
// What stays on screen with the panels hidden too: the heat-map legend, the comparison's
// labels, the help window and the hint that the panels are hidden.
void draw_overlays(const UiModel& model, ViewerSettings& settings);
// The heat-map legend's caption, tick marks and values alone (a screenshot with the overlay).
void draw_legend_labels(const UiModel& model, const ViewerSettings& settings);

}  // namespace flashgs::viewer
