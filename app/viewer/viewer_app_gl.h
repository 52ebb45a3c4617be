// ViewerApp: the viewer's frame loop tying together window, scene, navigation, frame path, presenter and panels.
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "camera_controller.h"
#include "camera_path.h"
#include "compare_mode.h"
#include "background_job.h"
#include "compare_task.h"
#include "file_browser_ui.h"
#include "file_dialog.h"
#include "debug_view_legend.h"
#include "heatmap_legend.h"
#include "lod_stream_view.h"
#include "path_editor.h"
#include "path_export.h"
#include "scene_lines.h"
#include "viewer_panels_ui.h"
#include "frame_path.h"
#include "scripted_run.h"
#include "scene_loader.h"
#include "scene_state.h"
#include "split_view.h"
#include "rate_meter.h"
#include "stats_history.h"
#include "viewer_args.h"
#include "viewer_settings.h"

namespace flashgs::viewer {

class Window;
class ImagePresenter;
class SplitViewPresenter;
class LineOverlay;
class ImGuiLayer;
struct UiActions;

class ViewerApp {
 public:
  explicit ViewerApp(ViewerArgs args);
  ~ViewerApp();
  // Runs until the window closes (or the script ends with --exit); returns the exit code.
  int run();

 private:
  // Setup.
  std::string settings_path() const;
  void restore_settings();  // from the config folder; a bad file: one line, the defaults
  void save_settings();     // interactive runs: at exit and when the recent files change
  void remember_recent(const std::string& path);
  bool open_window();  // window, GL, presenter, UI; false (message logged) when there is none
  void select_frame_path();
  // The CPU path (its frames on a worker thread); the one fallback when a GPU path fails.
  // `why` is logged as it is and shown in plain words.
  void use_cpu_path(const std::string& why);

  // Scenes (viewer_scenes_gl.cpp).
  bool start_first_scene();  // scripted: loads now; interactive: starts the load; false: stop
  bool apply_start_options();  // --tile (scripted), --render-size, --camera; false: a scripted run must stop
  bool open_scene(const std::string& path);  // loads now; false (error kept) on failure
  void request_open(const std::string& path);  // loads in the background (interactive runs)
  void request_lod_level(int level);  // another level of the SOG LOD set shown, loaded like a new file
  void start_stream();  // --stream, for the scene just installed
  // Hands the streamed cut for this view to the frame path as parts (assembled where the path
  // cannot draw parts with `options`); true when what is drawn changed (a new frame is needed).
  bool update_stream(const Camera& camera, const RenderOptions& options);
  // What the frame path draws: the streamed cut's parts once one was handed over, else the scene as one part.
  std::vector<ScenePart> drawn_parts() const;
  void finish_pending_load();
  void report_failed_load(const std::string& error);
  void install_scene(LoadedScene scene);
  // Navigation.
  void apply_up_choice();
  void snap_to_camera(int index);

  // One frame of the loop (run_one_frame): its steps, in order, and the steps they take.
  void run_one_frame();
  bool begin_frame(int* fb_w, int* fb_h, float* dt);  // events, sizes; false: nothing to draw into
  // The input (window or key script) and the panels, their actions applied; returns the navigation.
  NavigationInput take_input(int fb_w, int fb_h);
  void gather_input(NavigationInput& nav, UiActions& actions);
  // The keyboard's shortcuts and movement keys, where the panels leave the keyboard free.
  void read_keys(NavigationInput& nav, UiActions& actions);
  // The mouse's drags, clicks and wheel; `mouse_free`: the panels do not hold the mouse.
  void read_mouse(NavigationInput& nav, UiActions& actions, double x, double y, float dx, float dy, float scroll,
                  bool mouse_free);
  void apply_script_step(NavigationInput& nav);
  void build_panels(int fb_w, int fb_h, UiActions& actions);
  UiModel panel_model(int fb_w, int fb_h);  // what the panels show this frame
  void apply_actions(const UiActions& actions);
  // A finished load installed, the export's next frame, the camera moved.
  void advance_state(const NavigationInput& nav, float dt);
  bool advance_camera(const NavigationInput& nav, float dt);  // true: the view moves this frame
  // The frame requested or collected, a comparison's textures, the window drawn and swapped.
  void render_and_present(int fb_w, int fb_h);
  void request_frame(int fb_w, int fb_h, bool moving);
  void collect_frame();  // a finished frame: shown, its statistics kept
  void draw_and_present(int fb_w, int fb_h);
  // `rendering`: a background frame was in flight as this frame began (its UI time is tracked).
  void record_frame_times(double frame_ms, double ui_ms, bool rendering);
  void shut_down();  // after the loop: settings saved, a comparison stopped, the UI frames logged

  // The render size for this frame: `wanted`, or where it does not fit (memory, texture
  // limit) the last size that rendered, with one message logged and shown.
  void choose_render_size(int wanted_width, int wanted_height, int* width, int* height);
  void render_failed(int width, int height, const std::string& why);
  void set_notice(const std::string& message);  // logged once and shown in the panel
  void handle_escape(bool keys_free);
  void quit_now();
  bool m_quit_armed = false;  // a first Esc asked whether to quit
  void log_option_changes();
  void log_held_input();  // --log-input
  void log_popup_changes();  // --log-input: a test presses Esc only once the list it clicked is open
  bool m_logged_popup_open = false;
  void ensure_texture(int width, int height);
  void take_screenshot(const std::string& path);  // the rendered image, or with the heat map (setting)
  void legend_rect(int fb_w, int fb_h, float* rect) const;  // the heat-map legend, framebuffer pixels
  void save_screenshot(const std::string& path);
  void save_window_screenshot(const std::string& path, int width, int height);
  // The comparison of this view: started on its task (beside the frame loop on the CPU path);
  // finished once the task has it and its images are textures of the split view (GL, this
  // thread; one a frame unless `at_once`).
  void start_comparison();
  void finish_comparison(bool at_once);
  bool comparing() const;  // started, and not yet shown
  bool background_busy() const;  // a frame, a comparison or an export frame renders beside the loop
  bool comparison_shown() const;  // the split or difference image replaces the frame
  void handle_divider_drag(bool left_down, double x);
  int frustum_under_click(bool left_down, double x, double y);  // on release of a click, else -1
  void draw_guides(int fb_w, int fb_h);  // grid, axes and frustums over the frame
  float frustum_depth() const { return 0.08f * m_scene.extent; }  // how deep the frustums are drawn (and picked)
  void open_file_dialog();
  void start_path_export(const std::string& folder, int frames);
  void export_step();  // takes the export's finished frame and starts the next (or the video)
  std::string exported_frames_line() const;
  // Stops an export in progress: "path export VERB after N frames WHY" (a notice).
  void stop_path_export(const std::string& verb, const std::string& why);
  // The keyframed camera path (viewer_keyframes_gl.cpp).
  Camera view_for_key() const;        // the view as a key takes it
  void show_key_view(int index);      // the view jumps to key `index`
  void apply_key_actions(const UiActions& actions);
  bool load_keys(const std::string& file);  // false: not loaded (a notice says why)
  bool preview_keys(float dt);        // the preview moves the view: true while it plays
  void key_guides(std::vector<WorldSegment>& world) const;  // the keys and the curve over the scene
  void start_key_render(const std::string& folder);
  void log_legend();   // the heat-map legend's ticks, once per change
  // The debug view (depth, count) of the shown frame in place of its colour, when chosen and
  // the frame has its planes (viewer_debug_view_gl.cpp).
  void show_debug_view();
  void finish_script();
  void check_displayed_frame();

  ViewerArgs m_args;
  ViewerSettings m_settings;
  std::unique_ptr<Window> m_window;
  std::unique_ptr<ImagePresenter> m_presenter;
  std::unique_ptr<SplitViewPresenter> m_split;
  std::unique_ptr<LineOverlay> m_lines;
  std::unique_ptr<ImGuiLayer> m_ui;
  std::unique_ptr<FramePath> m_path;
  std::string m_path_note;  // in plain words (the log has the technical reason)
  bool m_path_is_cpu = true;

  LoadedScene m_scene;
  LodStreamView m_stream;       // --stream: the set drawn at the detail each view needs
  bool m_stream_was_loading = false;
  std::string m_load_error;  // the last failed load and what is shown instead
  SceneLoader m_loader;
  bool m_first_load_pending = false;  // the first scene loads in the background
  bool m_logged_load_progress = false;
  CameraController m_controller;
  std::unique_ptr<CameraPath> m_camera_path;
  int m_camera_index = -1;
  bool m_playing = false;
  double m_path_t = 0;

  // The last frame asked for (to ask again only when something changed) and the last shown.
  FrameRequest m_requested;
  bool m_have_request = false;
  bool m_requested_full = false;  // the last request was at the full render scale
  bool m_coarse_next_frame = false;  // a scene was installed: its first frame is a coarse one...
  bool m_coarse_in_flight = false;   // ...and it is being rendered
  Camera m_last_camera;
  RenderOptions m_last_options;
  bool m_have_frame = false;
  bool m_frame_is_full = false;  // the shown frame is at the full render scale
  bool m_logged_first_frame = false;
  bool m_delivered = false;  // a frame was delivered this loop iteration
  bool m_moving = false;     // the view moved in the last loop iteration
  std::chrono::steady_clock::time_point m_last_motion;  // when it last moved
  std::chrono::steady_clock::time_point m_frame_start, m_last_frame_start;
  std::chrono::steady_clock::time_point m_last_swap;  // the last frame's buffer swap
  FrameStats m_stats;
  StatsHistory m_history;
  std::vector<std::uint32_t> m_tile_counts;
  CompareResult m_compare;
  Camera m_compare_camera;          // the view and configuration the comparison was made for
  RenderOptions m_compare_options;
  CompareTask m_compare_task;
  CompareOutcome m_arrived;         // the finished comparison whose textures are going up...
  int m_arrived_textures = 0;       // ...and how many of its three are up (0: none arriving)
  std::string m_comparing;          // "flash vs baseline at WxH": the comparison the task runs
  float m_difference_factor = 1.0f;  // the difference image's magnification
  SplitDivider m_divider;
  bool m_left_was_down = false;
  int m_drag_frames = 0;       // frames a mouse button has been held (0: none held)
  bool m_drag_on_ui = false;   // the held press landed on an ImGui window
  double m_press_x = 0, m_press_y = 0;  // where the left button went down (a click snaps to a frustum)
  HeatScale m_heat_scale;
  Image m_debug_image;                         // the debug view on screen...
  FrameView m_debug_shown = FrameView::colour;  // ...which one it is (colour: none)
  DebugScale m_debug_scale;                    // ...and its scale (the legend's)
  std::string m_logged_debug_legend;
  std::string m_logged_legend;
  FileDialog m_dialog;
  FileBrowser m_browser;
  PathEditor m_keys;             // the keyframed camera path being authored
  PathFields m_key_fields;
  KeyframePath m_export_keys;    // the keyed path being rendered...
  bool m_export_from_keys = false;  // ...when the export renders it (else the loop through the cameras)
  PathExport m_export;
  BackgroundJob m_export_job;   // the export frame (or ffmpeg) in flight
  bool m_encoding_video = false;  // the job is ffmpeg making path.mp4
  std::string m_pending_overlay_shot;  // a screenshot of the image with the heat map and its legend...
  bool m_overlay_shot_frame = false;   // ...taken in this frame, which draws no panels
  bool m_compare_pending = false;  // asked for before there was a full frame to compare
  std::string m_status;
  RenderOptions m_logged_options;
  bool m_have_logged_options = false;
  RateMeter m_rendered_rate;  // finished frames per second (not loop wake-ups)
  double m_last_frame_ms = 0;  // wall time of the last finished frame
  float m_ui_scale = 1.0f;
  double m_full_render_ms = 0;  // wall time of the last render at the full render scale

  // The last frame size that rendered, and the render scale it came from: where to fall back
  // when a new size does not fit.
  int m_good_width = 0, m_good_height = 0;
  float m_good_scale = 1.0f;
  int m_checked_width = 0, m_checked_height = 0;  // the last size checked against memory...
  std::string m_checked_problem;                  // ...and why it does not fit (empty: fits)
  int m_max_texture_size = 0;                     // GL_MAX_TEXTURE_SIZE
  int m_ui_frames = 0;                            // frames presented with the panels since the first load
  int m_presented = 0;                            // frames presented in all
  // UI frames (input to swap, the wait for events not counted) while a frame or a comparison
  // rendered in the background: the worst is logged at exit (the UI must answer within 100 ms).
  int m_ui_frames_while_rendering = 0;
  double m_worst_ui_ms_while_rendering = 0;

  // Kept between runs (interactive runs only).
  bool m_persist = false;
  std::vector<std::string> m_recent;
  std::string m_stored_backend = "auto";

  // Input state between frames.
  double m_last_cursor_x = 0, m_last_cursor_y = 0;
  bool m_typing_in_path = false;  // Enter sent the path field: its typing goes on until a click
  std::string m_path_buffer, m_export_buffer;
  std::string m_pending_screenshot;  // waits for a full-resolution frame of the view

  // Scripted mode: the run's driver while it lasts (kept for its report).
  bool m_scripted = false;
  std::unique_ptr<ScriptedRun> m_script;
  double m_render_call_ms = 0, m_before_render_ms = 0, m_draw_ms = 0, m_swap_ms = 0;  // this frame's parts
  double m_compare_show_ms = 0;  // ...and the comparison's textures uploaded in it
  int m_exit_code = 0;
  std::string m_pending_window_shot;
  bool m_close_after_shot = false;
  std::chrono::steady_clock::time_point m_started = std::chrono::steady_clock::now();
  double ms_since_start() const;  // the viewer's own clock, for its log lines and rates
};

}  // namespace flashgs::viewer
