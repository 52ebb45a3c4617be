// The viewer's frame loop: input -> navigation -> render through the frame path -> present -> panels.
#include "viewer_app_gl.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "flashgs/gaussian_math.h"
#include "flashgs/error.h"
#include "flashgs/scene_summary.h"
#include "flashgs/renderer.h"
#include "count_text.h"
#include "gl_headers_gl.h"
#include "image_presenter_gl.h"
#include "imgui_layer_ui.h"
#include "flashgs/frame_memory.h"
#include "memory_budget.h"
#include "screenshot_names.h"
#include "line_overlay_gl.h"
#include "scene_lines.h"
#include "split_view_gl.h"
#include "path_note.h"
#include "process_clock.h"
#include "render_gate.h"
#include "settings_store.h"
#include "viewer_panels_ui.h"
#include "widget_places_ui.h"
#include "window_gl.h"

namespace flashgs::viewer {
namespace {

using Clock = std::chrono::steady_clock;
// While the view moves, a slow backend renders fewer pixels: about this long a frame (15 FPS).
constexpr double kMovingFrameMs = 66.0;
constexpr float kMinMovingScale = 0.25f;  // at most 1/16 of the pixels
// The view counts as moving until it has been still this long: a drag's pauses between mouse
// events do not ask for (and wait on) a full frame each time.
constexpr double kSettleMs = 200.0;

double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

bool same_camera(const Camera& a, const Camera& b) {
  if (a.width != b.width || a.height != b.height || a.fx != b.fx || a.fy != b.fy || a.cx != b.cx || a.cy != b.cy)
    return false;
  return std::equal(a.rotation, a.rotation + 9, b.rotation) && std::equal(a.position, a.position + 3, b.position);
}

glm::vec3 axis_from_text(const std::string& t) {
  glm::vec3 v(0.0f);
  const int axis = t[1] == 'x' ? 0 : (t[1] == 'y' ? 1 : 2);
  v[axis] = t[0] == '-' ? -1.0f : 1.0f;
  return v;
}

}  // namespace

double ViewerApp::ms_since_start() const { return ms_since(m_started); }

ViewerApp::ViewerApp(ViewerArgs args)
    : m_args(std::move(args)),
      m_compare_task([] { glfwPostEmptyEvent(); }),  // a finished comparison wakes the loop
      m_export_job([] { glfwPostEmptyEvent(); }) {   // as does each exported frame
  m_scripted = m_args.scripted();
  // The keyframed path's file: the one named, loaded when it exists (else saved there later).
  m_key_fields.file = m_args.camera_path.empty() ? "camera_path.json" : m_args.camera_path;
  m_key_fields.folder = "path_frames";
  if (!m_args.camera_path.empty() && std::filesystem::exists(m_args.camera_path) && !load_keys(m_args.camera_path) &&
      m_scripted)
    m_exit_code = 2;
  // Interactive runs start from the saved settings, the command line over them; scripted
  // runs from the defaults and the command line only (repeatable, and they save nothing).
  m_persist = !m_scripted && !config_dir().empty();
  if (m_persist) restore_settings();
  const ViewerArgs defaults;
  auto given = [&](bool differs) { return m_scripted || differs; };
  RenderOptions& o = m_settings.options;
  if (given(m_args.algorithm != defaults.algorithm))
    switch_algorithm(o, m_args.algorithm == "baseline" ? Algorithm::baseline : Algorithm::flash);
  if (given(m_args.tau != defaults.tau)) o.tau = m_args.tau;
  if (given(m_args.sh_degree != defaults.sh_degree)) o.sh_degree_cap = m_args.sh_degree;
  if (given(m_args.fp16_sh != defaults.fp16_sh)) o.fp16_sh = m_args.fp16_sh;
  if (given(m_args.fp16_shape != defaults.fp16_shape)) o.fp16_shape = m_args.fp16_shape;
  if (given(m_args.fp16_blend != defaults.fp16_blend)) o.fp16_blend = m_args.fp16_blend;
  m_args.switches.apply(&o);
  if (given(m_args.background != defaults.background))
    for (int c = 0; c < 3; ++c) o.background[c] = m_args.background[c];
  if (given(m_args.scale != defaults.scale)) m_settings.render_scale = m_args.scale;
  m_good_scale = m_settings.render_scale;
  m_settings.forced_width = m_args.render_width;
  m_settings.forced_height = m_args.render_height;
  m_settings.heatmap = m_args.heatmap;
  m_settings.lod_overlay = m_args.lod_overlay;
  if (given(m_args.orbit)) m_settings.mode = m_args.orbit ? NavigationMode::orbit : NavigationMode::fly;  // auto: install_scene
  m_settings.show_ui = !m_args.no_ui;
  m_settings.show_help = m_args.help_window;
  m_settings.screenshot_overlay = m_args.screenshot_overlay;
  m_settings.show_grid = m_args.grid;
  m_settings.show_centres = m_args.centres;
  parse_frame_view(m_args.view, &m_settings.view);  // checked by the option
  m_settings.show_frustums = m_args.frustums;
  m_settings.up_axis = int(std::find(kUpAxisNames, kUpAxisNames + kUpAxisCount, m_args.up) - kUpAxisNames) % kUpAxisCount;
  m_settings.compare_view = m_args.compare_view == "numbers" ? CompareView::numbers
                            : m_args.compare_view == "difference" ? CompareView::difference : CompareView::split;
  m_settings.compare_left = std::max(0, compare_choice_from_name(m_args.compare_left));
  m_settings.compare_right = std::max(0, compare_choice_from_name(m_args.compare_right));
  m_divider.set_fraction(m_args.split_at);
  m_settings.screenshot_folder = m_args.screenshot_dir.empty() ? default_screenshot_folder() : m_args.screenshot_dir;
  if (m_scripted) m_settings.vsync = false;
  else if (m_args.no_vsync) m_settings.vsync = false;
  if (m_persist && m_args.backend == defaults.backend) m_args.backend = m_stored_backend;
  if (m_scripted) {
    ScriptedRunPlan plan;
    plan.keys = m_args.keys;
    plan.path = m_args.path;
    plan.frames = m_args.frames;
    plan.warmup = m_args.warmup;
    plan.then_open = !m_args.then_open.empty();
    m_script = std::make_unique<ScriptedRun>(plan);  // throws on a malformed --keys
  }
}

std::string ViewerApp::settings_path() const { return config_dir() + "/settings.ini"; }

void ViewerApp::restore_settings() {
  StoredSettings stored;
  stored.settings = m_settings;
  const std::string problem = read_settings_file(settings_path(), stored);
  if (!problem.empty()) {
    set_notice(problem);
    return;
  }
  m_settings = stored.settings;
  m_recent = stored.recent;
  m_stored_backend = stored.backend;
  std::error_code ec;
  if (std::filesystem::exists(settings_path(), ec))  // not on the first run
    std::fprintf(stderr, "flashgs-viewer: settings from %s (%zu recent files)\n", settings_path().c_str(), m_recent.size());
}

void ViewerApp::save_settings() {
  if (!m_persist) return;
  StoredSettings stored;
  stored.settings = m_settings;
  stored.backend = m_args.backend;
  stored.recent = m_recent;
  const std::string problem = write_settings_file(settings_path(), stored);
  if (!problem.empty()) set_notice("settings " + problem);
  else std::fprintf(stderr, "flashgs-viewer: settings saved to %s\n", settings_path().c_str());
}

void ViewerApp::remember_recent(const std::string& path) {
  if (!m_persist || path.empty()) return;
  add_recent_file(m_recent, path);
  save_settings();  // now: a crash later keeps the list
}

ViewerApp::~ViewerApp() {
  // A comparison and an export frame render through the path: they stop first.
  m_compare_task.cancel();
  m_compare_task.wait();
  m_export_job.cancel();
  m_export_job.wait();
  // GL objects and interop registrations go before the context (the window) does.
  m_path.reset();
  m_split.reset();
  m_ui.reset();
  m_presenter.reset();
  m_window.reset();
}

void ViewerApp::use_cpu_path(const std::string& why) {
  if (m_compare_task.busy()) {  // it renders through the path being replaced
    m_compare_task.cancel();
    m_compare_task.wait();
  }
  stop_path_export("stopped", ": the frame path changed");
  if (m_export_job.busy() && !m_encoding_video) {  // its frame renders through the path being replaced (ffmpeg does not)
    m_export_job.wait();
    std::string dropped;
    m_export_job.take(&dropped);
  }
  // The worker wakes the event loop when a frame is done: the window shows it at once.
  std::unique_ptr<Renderer> renderer = make_cpu_renderer(m_args.cpu_threads);
  if (!m_args.render_gate.empty()) {
    renderer = std::make_unique<FileGatedRenderer>(std::move(renderer), m_args.render_gate);
    std::fprintf(stderr, "flashgs-viewer: each render waits for %s (--render-gate)\n", m_args.render_gate.c_str());
  }
  m_path = make_background_upload_path(std::move(renderer), m_presenter.get(), "CPU renderer + texture upload",
                                       [] { glfwPostEmptyEvent(); });
  m_path_is_cpu = true;
  m_path_note = plain_path_note(why);
  // On the CPU a frame takes long: re-render only when something changes.
  m_settings.continuous = false;
  m_have_request = false;
  std::fprintf(stderr, "flashgs-viewer: frame path: %s (%s)\n", m_path->name().c_str(), why.c_str());
  if (m_scene.scene) m_path->set_scene(m_scene.scene);
  m_stream.hand_over_again();  // a streamed cut goes to the new path at the next frame
}

void ViewerApp::select_frame_path() {
  if (m_args.backend == "cpu") {
    use_cpu_path("--backend cpu");
    return;
  }
  std::string why;
  std::unique_ptr<FramePath> cuda;
  try {
    cuda = make_cuda_path(m_presenter.get(), &why);
  } catch (const std::exception& e) {
    why = std::string("CUDA path failed: ") + e.what();
  }
  if (!cuda) {
    use_cpu_path(why);
    return;
  }
  m_path = std::move(cuda);
  m_path_is_cpu = false;
  m_path_note = plain_path_note(why);  // empty when interop works; otherwise why the host copy is used
  m_settings.continuous = true;  // GPU paths render every frame and show their FPS
  std::fprintf(stderr, "flashgs-viewer: frame path: %s%s%s%s\n", m_path->name().c_str(), why.empty() ? "" : " (",
               why.c_str(), why.empty() ? "" : ")");
}

void ViewerApp::apply_up_choice() {
  glm::vec3 up = m_settings.up_axis == 0 ? m_scene.up : axis_from_text(kUpAxisNames[m_settings.up_axis]);
  m_controller.reset(m_scene.centre, m_scene.extent, up);
  if (m_settings.flip_up) m_controller.flip_up();
}

void ViewerApp::snap_to_camera(int index) {
  if (m_scene.cameras.empty()) return;
  const int n = static_cast<int>(m_scene.cameras.size());
  index = ((index % n) + n) % n;
  m_camera_index = index;
  m_controller.snap_to(m_scene.cameras[index]);
  m_settings.fov_x_degrees = m_scene.cameras[index].horizontal_fov_degrees();
  m_playing = false;
}

void ViewerApp::gather_input(NavigationInput& nav, UiActions& actions) {
  double x = 0, y = 0;
  m_window->cursor(&x, &y);
  const float dx = float(x - m_last_cursor_x), dy = float(y - m_last_cursor_y);
  m_last_cursor_x = x;
  m_last_cursor_y = y;
  const float scroll = m_window->take_scroll();
  for (const std::string& p : m_window->take_drops())
    if (actions.open_path.empty()) actions.open_path = p;

  // ImGui runs with the panels hidden too (legend, help): its windows still take the input.
  const bool mouse_free = !(m_ui && m_ui->wants_mouse());
  read_keys(nav, actions);
  read_mouse(nav, actions, x, y, dx, dy, scroll, mouse_free);
}

void ViewerApp::read_keys(NavigationInput& nav, UiActions& actions) {
  // After Enter in the path field the typing goes on there (the field takes the focus back a
  // frame or two later): until a click, letters are text, not shortcuts.
  if (m_window->mouse_down(GLFW_MOUSE_BUTTON_LEFT) || m_window->mouse_down(GLFW_MOUSE_BUTTON_RIGHT))
    m_typing_in_path = false;
  const bool keys_free = !(m_ui && m_ui->wants_keyboard()) && !m_typing_in_path;
  const std::vector<KeyPress> presses = m_window->take_key_presses();
  // Esc leaves the field (ImGui ends its edit): the next keys are shortcuts again.
  if (std::any_of(presses.begin(), presses.end(), [](const KeyPress& p) { return p.key == GLFW_KEY_ESCAPE; }))
    m_typing_in_path = false;
  int mods = 0;
  auto pressed = [&](int key) {  // a press event since the last frame; `mods` its modifiers
    for (const KeyPress& p : presses)
      if (keys_free && p.key == key) {
        mods = p.mods;
        return true;
      }
    return false;
  };
  if (keys_free) {
    nav.forward = m_window->key_down(GLFW_KEY_W);
    // Ctrl+S saves the camera path: it does not also move the view back.
    nav.back = m_window->key_down(GLFW_KEY_S) && !m_window->key_down(GLFW_KEY_LEFT_CONTROL) &&
               !m_window->key_down(GLFW_KEY_RIGHT_CONTROL);
    nav.left = m_window->key_down(GLFW_KEY_A);
    nav.right = m_window->key_down(GLFW_KEY_D);
    nav.down = m_window->key_down(GLFW_KEY_Q);
    nav.up = m_window->key_down(GLFW_KEY_E);
    nav.fast = m_window->key_down(GLFW_KEY_LEFT_SHIFT) || m_window->key_down(GLFW_KEY_RIGHT_SHIFT);
  }
  if (pressed(GLFW_KEY_N)) actions.next_camera = true;
  if (pressed(GLFW_KEY_P)) actions.previous_camera = true;
  if (pressed(GLFW_KEY_SPACE)) actions.toggle_play = true;
  if (pressed(GLFW_KEY_C)) actions.compare = true;
  if (pressed(GLFW_KEY_H)) m_settings.heatmap = !m_settings.heatmap;
  if (pressed(GLFW_KEY_V)) m_settings.view = next_frame_view(m_settings.view);
  if (pressed(GLFW_KEY_F1)) {
    m_settings.show_help = !m_settings.show_help;
    std::fprintf(stderr, "flashgs-viewer: help %s (F1)\n", m_settings.show_help ? "shown" : "closed");
  }
  if (pressed(GLFW_KEY_TAB)) {
    m_settings.show_ui = !m_settings.show_ui;
    std::fprintf(stderr, "flashgs-viewer: panels %s (Tab)\n", m_settings.show_ui ? "shown" : "hidden");
  }
  if (pressed(GLFW_KEY_F)) actions.frame_scene = true;
  if (pressed(GLFW_KEY_G)) m_settings.show_grid = !m_settings.show_grid;
  if (pressed(GLFW_KEY_I)) actions.add_key = true;
  if (pressed(GLFW_KEY_S) && (mods & GLFW_MOD_CONTROL)) actions.save_keys = true;
  // Any other key or a click takes back a first Esc (see handle_escape).
  if (std::any_of(presses.begin(), presses.end(), [](const KeyPress& p) { return p.key != GLFW_KEY_ESCAPE; }) ||
      m_window->mouse_down(GLFW_MOUSE_BUTTON_LEFT) || m_window->mouse_down(GLFW_MOUSE_BUTTON_RIGHT))
    m_quit_armed = false;
  if (pressed(GLFW_KEY_Q) && (mods & GLFW_MOD_CONTROL)) quit_now();
  // Esc reaches an open popup however ImGui holds the keyboard; otherwise only a free keyboard's.
  if (std::any_of(presses.begin(), presses.end(), [](const KeyPress& p) { return p.key == GLFW_KEY_ESCAPE; }))
    handle_escape(keys_free);
  if (pressed(GLFW_KEY_O) && (mods & GLFW_MOD_CONTROL)) actions.open_dialog = true;
  if (pressed(GLFW_KEY_F12)) {
    if (mods & GLFW_MOD_SHIFT) m_pending_window_shot = next_screenshot_path(m_settings.screenshot_folder, "window");
    else actions.screenshot = true;
  }
  if (pressed(GLFW_KEY_O) && !(mods & GLFW_MOD_CONTROL))
    m_settings.mode = m_settings.mode == NavigationMode::fly ? NavigationMode::orbit : NavigationMode::fly;
  for (int key : {GLFW_KEY_EQUAL, GLFW_KEY_KP_ADD})
    if (pressed(key)) nav.speed_steps += 1.0f;
  for (int key : {GLFW_KEY_MINUS, GLFW_KEY_KP_SUBTRACT})
    if (pressed(key)) nav.speed_steps -= 1.0f;
  if (pressed(GLFW_KEY_B))
    switch_algorithm(m_settings.options, m_settings.options.is_baseline() ? Algorithm::flash : Algorithm::baseline);
  if (pressed(GLFW_KEY_K)) {
    m_settings.options.kernel = next_trainer_kernel(m_settings.options.kernel);
    std::fprintf(stderr, "flashgs-viewer: kernel: %s (K)\n", m_settings.options.kernel.description().c_str());
  }
}

void ViewerApp::read_mouse(NavigationInput& nav, UiActions& actions, double x, double y, float dx, float dy,
                           float scroll, bool mouse_free) {
  const bool left_down = m_window->mouse_down(GLFW_MOUSE_BUTTON_LEFT);
  if (mouse_free) actions.snap_camera = frustum_under_click(left_down, x, y);
  if (mouse_free || m_divider.dragging()) handle_divider_drag(left_down, x);
  // A press belongs to the panel it lands on, but ImGui says so only from the next frame (its
  // capture is computed after this input), and the cursor may have jumped to the press: the
  // view is dragged from a drag's second frame on, and only if ImGui did not take the press.
  const bool right_down = m_window->mouse_down(GLFW_MOUSE_BUTTON_RIGHT);
  const bool middle_down = m_window->mouse_down(GLFW_MOUSE_BUTTON_MIDDLE);
  if (!(left_down || right_down || middle_down)) m_drag_frames = 0;
  else if (++m_drag_frames == 2) m_drag_on_ui = !mouse_free;
  const bool view_drag = m_drag_frames >= 2 && !m_drag_on_ui;
  if (mouse_free && !m_divider.dragging()) {
    const bool left = left_down && view_drag;
    const bool right = right_down && view_drag;
    const bool middle = middle_down && view_drag;
    // As in SIBR, SuperSplat and viser: left-drag looks (fly) or orbits, right/middle-drag
    // (or Shift+left) pans, the wheel dollies and Ctrl+wheel sets the speed.
    if (left && !nav.fast) nav.look_dx = dx, nav.look_dy = dy;
    if (right || middle || (left && nav.fast)) nav.pan_dx = dx, nav.pan_dy = dy;
    const bool ctrl = m_window->key_down(GLFW_KEY_LEFT_CONTROL) || m_window->key_down(GLFW_KEY_RIGHT_CONTROL);
    if (ctrl) nav.speed_steps += scroll;
    else nav.scroll = scroll;
  }
  m_left_was_down = left_down;
}

void ViewerApp::apply_actions(const UiActions& a) {
  if (a.cancel_load && m_loader.busy()) {
    set_notice("stopped waiting for " + m_loader.path());
    m_loader.abandon();
  }
  if (!a.open_path.empty()) request_open(a.open_path);
  if (a.path_entered) m_typing_in_path = true;
  if (a.lod_level >= 0) request_lod_level(a.lod_level);
  if (a.snap_camera >= 0) snap_to_camera(a.snap_camera);
  if (a.next_camera) snap_to_camera(m_camera_index + 1);
  if (a.previous_camera) snap_to_camera(m_camera_index < 0 ? 0 : m_camera_index - 1);
  if (a.toggle_play && m_camera_path && !m_camera_path->empty()) {
    m_playing = !m_playing;
    if (m_playing) {
      m_path_t = m_camera_index >= 0 ? double(m_camera_index) / m_camera_path->size() : 0.0;
      std::fprintf(stderr, "flashgs-viewer: playing the camera path: %zu cameras, %.2f s each\n",
                   m_camera_path->size(), m_settings.path_seconds_per_camera);
    }
  }
  if (a.flip_up) m_controller.flip_up();
  if (a.reset_view) {
    m_settings.flip_up = m_args.flip_up;
    apply_up_choice();
    m_camera_index = -1;
  }
  if (a.frame_scene)
    m_controller.frame_scene(m_settings.fov_x_degrees,
                             m_have_frame ? float(m_last_camera.width) / float(m_last_camera.height) : 16.0f / 9.0f);
  if (a.up_changed) {
    apply_up_choice();
    m_camera_index = -1;
  }
  if (a.open_dialog) open_file_dialog();
  if (!a.export_folder.empty()) start_path_export(a.export_folder, m_args.export_frames);
  if (a.cancel_export) stop_path_export("cancelled", "");
  apply_key_actions(a);
  if (a.screenshot) {
    // The picture of the view at full resolution: a scripted run has it now; an interactive
    // one may still be rendering it (or showing a reduced frame) and saves it once it is shown.
    const std::string path = next_screenshot_path(m_settings.screenshot_folder, "");
    if (m_scripted) take_screenshot(path);
    else m_pending_screenshot = path;
  }
  // Asked for before the first frame (the scene still loading or rendering): once it is there.
  if (a.compare) m_compare_pending = true;
  if (m_compare_pending && m_have_frame && m_frame_is_full) {
    m_compare_pending = false;
    start_comparison();
  }
}

void ViewerApp::start_comparison() {
  if (comparing()) {
    set_notice("still comparing " + m_comparing + ": this request is ignored");
    return;
  }
  CompareJob job;
  job.camera = m_last_camera;
  job.left = compare_choice_options(m_settings.compare_left, m_settings.options);
  job.right = compare_choice_options(m_settings.compare_right, m_settings.options);
  job.rounds = m_args.compare_rounds;
  try {  // the GPU's pool draws neither the baseline nor fp16 storage: the cut assembled for them
    const std::string assembled = m_stream.assemble_for({job.left, job.right}, *m_path);
    if (!assembled.empty())
      std::fprintf(stderr, "flashgs-viewer: the streamed cut goes to the renderer assembled: %s\n", assembled.c_str());
  } catch (const std::exception& e) {
    set_notice("comparison refused: the streamed cut could not be assembled: " + error_text(e));
    return;
  }
  m_compare = {};  // the last comparison's images are of another view: the frame shows meanwhile
  m_compare_camera = m_last_camera;
  m_compare_options = m_last_options;
  m_comparing = job.right.label() + " vs " + job.left.label() + " at " + size_text(job.camera.width, job.camera.height);
  if (m_path->renders_in_background())
    std::fprintf(stderr, "flashgs-viewer: comparing %s in the background\n", m_comparing.c_str());
  m_compare_task.start(*m_path, job);
}

bool ViewerApp::comparing() const { return m_compare_task.busy() || m_arrived_textures > 0; }

bool ViewerApp::background_busy() const { return m_path->busy() || comparing() || m_export_job.busy(); }

void ViewerApp::finish_comparison(bool at_once) {
  CompareOutcome& done = m_arrived;
  if (m_arrived_textures == 0) {
    if (!m_compare_task.take(&done)) return;
    if (done.cancelled()) {  // another scene, or quitting
      std::fprintf(stderr, "flashgs-viewer: comparison of %s cancelled after %.0f ms\n", m_comparing.c_str(),
                   done.elapsed_ms);
      return;
    }
    if (!done.result.valid) {
      m_compare = std::move(done.result);
      set_notice("compare: " + m_compare.error);
      return;
    }
    if (!m_split) {
      m_split = std::make_unique<SplitViewPresenter>();
      m_split->init();
    }
  }
  // One texture a frame unless `at_once`: each takes about a frame's time on llvmpipe.
  const std::uint8_t* textures[3] = {done.left_rgba.data(), done.right_rgba.data(), done.difference_rgba.data()};
  do {
    m_split->set_image(m_arrived_textures, done.result.width, done.result.height, textures[m_arrived_textures]);
  } while (++m_arrived_textures < 3 && at_once);
  if (m_arrived_textures < 3) return;
  m_arrived_textures = 0;
  m_compare = std::move(done.result);
  m_difference_factor = done.difference_factor;
  std::fprintf(stderr,
               "flashgs-viewer: compare %s vs %s at %dx%d: PSNR %.2f dB, max abs %.6f, median %.3f ms (%.3f-%.3f) "
               "vs %.3f ms (%.3f-%.3f), %s, pair reduction %.1f%%, difference image x%.0f\n",
               m_compare.right_label.c_str(), m_compare.left_label.c_str(), m_compare.width, m_compare.height,
               m_compare.difference.psnr_db, m_compare.difference.max_abs, m_compare.right_ms.median,
               m_compare.right_ms.min, m_compare.right_ms.max, m_compare.left_ms.median, m_compare.left_ms.min,
               m_compare.left_ms.max, speed_up_text(m_compare).c_str(), 100.0 * m_compare.pair_reduction(),
               m_difference_factor);
  // The view or configuration asked for while it ran is not the one compared.
  if (m_have_request && (!same_camera(m_requested.camera, m_compare_camera) || !(m_requested.options == m_compare_options))) {
    m_compare.stale = true;
    std::fprintf(stderr, "flashgs-viewer: the comparison is stale: the view or options changed in its %.0f ms\n",
                 done.elapsed_ms);
  }
  done = CompareOutcome{};
}

bool ViewerApp::comparison_shown() const {
  return m_split && m_compare.valid && !m_compare.stale && m_settings.compare_view != CompareView::numbers;
}

void ViewerApp::handle_divider_drag(bool left_down, double x) {
  int width = 0, height = 0;
  m_window->window_size(&width, &height);
  const bool split = comparison_shown() && m_settings.compare_view == CompareView::split;
  if (left_down && !m_left_was_down && split) m_divider.press(float(x), float(width));
  else if (left_down && m_divider.dragging()) m_divider.drag_to(float(x), float(width));
  else if (!left_down) m_divider.release();
}

int ViewerApp::frustum_under_click(bool left_down, double x, double y) {
  const bool pressed_now = left_down && !m_left_was_down, released_now = !left_down && m_left_was_down;
  if (pressed_now) m_press_x = x, m_press_y = y;
  if (!released_now || !m_settings.show_frustums || !m_have_frame || m_divider.dragging()) return -1;
  if (std::hypot(x - m_press_x, y - m_press_y) > 4.0) return -1;  // a drag, not a click
  int width = 0, height = 0;
  m_window->window_size(&width, &height);
  if (width <= 0 || height <= 0) return -1;
  const float sx = float(m_last_camera.width) / float(width), sy = float(m_last_camera.height) / float(height);
  const int index = pick_camera(m_scene.cameras, m_last_camera, float(x) * sx, float(y) * sy, 8.0f * sx,
                                frustum_depth());
  if (index >= 0) std::fprintf(stderr, "flashgs-viewer: clicked the frustum of camera %d\n", index);
  return index;
}

void ViewerApp::draw_guides(int fb_w, int fb_h) {
  if (!(m_settings.show_grid || m_settings.show_frustums || m_settings.show_centres || !m_keys.path().keys.empty()) ||
      !m_have_frame)
    return;
  if (!m_lines) {
    m_lines = std::make_unique<LineOverlay>();
    m_lines->init();
  }
  std::vector<WorldSegment> world;
  if (m_settings.show_grid) world = grid_and_axes(m_scene.centre, m_scene.extent, m_controller.world_up());
  if (m_settings.show_frustums) {
    const std::vector<WorldSegment> f = camera_frustums(m_scene.cameras, frustum_depth(),
                                                        m_controller.on_scene_camera() ? m_camera_index : -1);
    world.insert(world.end(), f.begin(), f.end());
  }
  key_guides(world);
  std::vector<ScreenSegment> screen = project_segments(world, m_last_camera, 1e-3f * m_scene.extent);
  if (m_settings.show_centres && m_scene.scene) {
    const std::vector<ScreenSegment> dots = centre_marks(drawn_parts(), m_last_camera, kMaxCentreMarks);
    screen.insert(screen.end(), dots.begin(), dots.end());
  }
  m_lines->draw(screen, m_last_camera.width, m_last_camera.height, fb_w, fb_h);
}

void ViewerApp::open_file_dialog() {
  const std::string folder = m_scene.path.empty() ? std::string(".")
                                                  : std::filesystem::path(m_scene.path).parent_path().string();
  if (m_dialog.busy() || m_browser.is_open()) return;
  if (m_dialog.open_native(folder)) {
    std::fprintf(stderr, "flashgs-viewer: file dialog: %s\n", m_dialog.tool().c_str());
  } else {
    std::fprintf(stderr, "flashgs-viewer: file dialog: in-app browser (no zenity or kdialog on PATH)\n");
    m_browser.open(folder);
  }
}

void ViewerApp::log_legend() {
  // One line per change: tests read the ticks the legend shows.
  std::string text = legend_caption(gm::kTileSize, m_settings.heatmap_log, m_settings.heatmap_lock_max) + ", ticks";
  for (const LegendTick& t : legend_ticks(m_heat_scale.max(), m_settings.heatmap_log))
    text += " " + std::to_string(t.value) + "@" + std::to_string(int(std::lround(t.position * 100))) + "%";
  if (text == m_logged_legend) return;
  m_logged_legend = text;
  std::fprintf(stderr, "flashgs-viewer: heat-map legend: %s\n", text.c_str());
}

void ViewerApp::ensure_texture(int width, int height) {
  if (!m_presenter->needs_resize(width, height, m_path->texture_count())) return;
  m_path->release_textures();
  m_presenter->resize(width, height, m_path->texture_count());
  try {
    GLuint textures[ImagePresenter::kMaxTextures] = {};
    for (int i = 0; i < m_path->texture_count(); ++i) textures[i] = m_presenter->texture(i);
    m_path->attach_textures(textures, width, height);
  } catch (const std::exception& e) {
    use_cpu_path(std::string("interop failed: ") + e.what());
  }
}

void ViewerApp::request_frame(int fb_w, int fb_h, bool moving) {
  m_render_call_ms = 0;
  if (!m_scene.scene) return;
  // The coarse first frame of a scene is not replaced while it renders: the next request
  // (the full frame) would cancel it, and the window would stay empty until that one ends.
  if (m_coarse_in_flight && m_path->busy()) return;
  m_coarse_in_flight = false;
  // A slow backend renders fewer pixels while the view moves (about kMovingFrameMs a frame),
  // and the full frame once it stops: the camera then differs, so it is asked for again.
  float scale = m_settings.render_scale;
  // A screenshot waits for a full frame: none is reduced (or stopped) until it is taken.
  const bool shot_pending = !m_pending_screenshot.empty();
  // The first frame of a new scene is coarse too: its full frame's time is not known yet.
  // (A fixed --render-size has no coarser size.)
  const bool coarse_first = !m_scripted && m_settings.adaptive_resolution && m_coarse_next_frame && !shot_pending &&
                            m_settings.forced_width == 0;
  const bool reduced = coarse_first || (!m_scripted && m_settings.adaptive_resolution && moving &&
                                        m_full_render_ms > kMovingFrameMs && !shot_pending);
  if (coarse_first) scale *= kMinMovingScale;
  else if (reduced) scale *= std::clamp(float(std::sqrt(kMovingFrameMs / m_full_render_ms)), kMinMovingScale, 1.0f);
  m_coarse_in_flight = coarse_first;
  m_coarse_next_frame = false;
  const int wanted_w = m_settings.forced_width > 0 ? m_settings.forced_width : std::max(1, int(std::lround(fb_w * scale)));
  const int wanted_h = m_settings.forced_height > 0 ? m_settings.forced_height : std::max(1, int(std::lround(fb_h * scale)));
  int rw = 0, rh = 0;
  choose_render_size(wanted_w, wanted_h, &rw, &rh);
  FrameRequest request;
  request.camera = m_controller.render_camera(rw, rh, m_settings.fov_x_degrees);
  request.options = m_settings.options;
  request.options.collect_tile_counts = m_settings.heatmap;  // counts cost a copy: only when shown
  request.options.collect_pixel_planes = m_settings.view != FrameView::colour;
  request.reduced = reduced;
  const bool streamed = m_stream.active() && update_stream(request.camera, request.options);
  const bool changed = streamed || !m_have_request || !same_camera(request.camera, m_requested.camera) ||
                       request.options != m_requested.options;
  const bool again = m_scripted || (m_settings.continuous && !m_path->busy());
  if (!changed && !again) return;
  // While the view moves or a widget is held (a slider dragged), the frame in flight finishes
  // and the newest request renders next: such changes come every UI frame, faster than a frame
  // renders, so cancelling each would show nothing until they end. Only a full frame too slow for
  // a moving view stops for the first reduced one; any other change (a click, the view coming to
  // rest) replaces whatever is in flight.
  const bool changing = moving || (m_ui && m_ui->widget_held());
  const bool cancel_in_flight = !shot_pending && (!changing || (m_requested_full && reduced));
  const auto t0 = Clock::now();
  try {
    if (!m_path->renders_in_background()) ensure_texture(rw, rh);
    try {
      m_path->submit(request, cancel_in_flight);
    } catch (const std::exception& e) {
      if (m_path_is_cpu) throw;
      use_cpu_path(std::string("CUDA frame failed: ") + e.what());  // the one fallback
      m_path->submit(request, true);
    }
  } catch (const std::exception& e) {  // out of memory, a texture refused: keep running
    render_failed(rw, rh, error_text(e));
  }
  m_requested = request;
  m_have_request = true;
  m_requested_full = !reduced;
  // Scripted runs time and check each frame: they wait for it (an event, not a sleep).
  if (m_scripted) m_path->wait_until_idle();
  m_render_call_ms = ms_since(t0);
}

void ViewerApp::collect_frame() {
  m_delivered = false;
  FinishedFrame frame;
  try {
    if (!m_path->take_finished(&frame)) return;
  } catch (const std::exception& e) {  // the upload's texture refused
    render_failed(frame.request.camera.width, frame.request.camera.height, error_text(e));
    return;
  }
  const int width = frame.request.camera.width, height = frame.request.camera.height;
  if (!frame.error.empty()) {
    render_failed(width, height, frame.error);
    return;
  }
  m_delivered = true;
  m_stats = std::move(frame.stats);
  m_last_camera = frame.request.camera;
  m_last_options = frame.request.options;
  m_have_frame = true;
  m_frame_is_full = !frame.request.reduced;
  m_last_frame_ms = frame.wall_ms;
  m_rendered_rate.record(ms_since_start() / 1000.0);
  if (m_frame_is_full) {
    m_full_render_ms = frame.wall_ms;
    m_good_scale = m_settings.render_scale;
  }
  m_good_width = width;
  m_good_height = height;
  if (m_last_options.collect_tile_counts) {
    // The overlay's counts are this frame's: show this frame too, not the one before it.
    m_path->present_latest();
    m_path->tile_counts(m_stats, m_tile_counts);
    std::uint32_t max_count = m_stats.max_tile_pairs;
    if (max_count == 0)
      for (std::uint32_t c : m_tile_counts) max_count = std::max(max_count, c);
    const std::uint64_t top = m_heat_scale.update(max_count, m_settings.heatmap_lock_max);
    m_presenter->set_tile_counts(m_tile_counts, m_stats.tiles_x, m_stats.tiles_y,
                                 static_cast<std::uint32_t>(std::min<std::uint64_t>(top, UINT32_MAX)));
    log_legend();
  }
  // Another view or configuration than the comparison's: its images no longer match the frame.
  if (m_compare.valid && (!same_camera(m_last_camera, m_compare_camera) || !(m_last_options == m_compare_options)))
    m_compare.stale = true;
  if (m_args.log_input)
    std::fprintf(stderr, "flashgs-viewer: frame shown %dx%d (%s) rendered in %.0f ms\n", width, height,
                 m_frame_is_full ? "full" : "reduced", frame.wall_ms);
  if (!m_logged_first_frame && m_frame_is_full) {
    m_logged_first_frame = true;
    std::fprintf(stderr, "flashgs-viewer: first frame shown %.0f ms after start (%.0f ms after the process started) "
                 "(%dx%d, %s)\n", ms_since_start(), ms_since_process_start(), width, height, m_scene.path.c_str());
  }
}

void ViewerApp::legend_rect(int fb_w, int fb_h, float* rect) const {
  // Bottom right, clear of the main panel (top left) and the statistics (top right).
  const float u = m_ui_scale * m_window->framebuffer_scale();
  rect[0] = float(fb_w) - (20.0f + kLegendBarPoints) * u;
  // Room below the bar for the tick labels, above it for the caption.
  rect[1] = float(fb_h) - 46.0f * u;
  rect[2] = float(fb_w) - 20.0f * u;
  rect[3] = float(fb_h) - 32.0f * u;
}

void ViewerApp::draw_and_present(int fb_w, int fb_h) {
  // Showing the previous frame while this one renders pays only when another frame follows at
  // once (a GPU path rendering every frame); otherwise the newest is shown.
  if (!(m_delivered && (m_settings.continuous || m_scripted))) m_path->present_latest();
  m_presenter->show(m_path->shown_texture());
  if (m_debug_shown != FrameView::colour) m_presenter->show(0);  // show_debug_view uploaded it there
  HeatmapView heat;
  heat.log_scale = m_settings.heatmap_log;
  heat.opacity = m_settings.heatmap_opacity;
  legend_rect(fb_w, fb_h, heat.legend_rect);
  glClearColor(0, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT);
  const auto t_draw = Clock::now();
  // Until the first frame there is no texture: the window shows the panels (and the load's progress).
  const bool comparing = comparison_shown();
  if (m_presenter->width() > 0)
    m_presenter->draw(fb_w, fb_h, m_settings.heatmap && m_have_frame && !comparing ? &heat : nullptr);
  if (!comparing) draw_guides(fb_w, fb_h);
  if (comparing)
    m_split->draw(fb_w, fb_h, m_divider.fraction(), std::max(2.0f, 2.0f * m_ui_scale * m_window->framebuffer_scale()),
                  m_settings.compare_view == CompareView::difference);
  m_ui->end_frame();
  if (m_overlay_shot_frame) {  // the image as shown, heat map and legend included, panels not
    save_window_screenshot(m_pending_overlay_shot, fb_w, fb_h);
    m_status = "saved " + m_pending_overlay_shot + " (heat map included)";
    m_pending_overlay_shot.clear();
    m_overlay_shot_frame = false;
  }
  if (!m_pending_window_shot.empty()) {
    save_window_screenshot(m_pending_window_shot, fb_w, fb_h);
    m_pending_window_shot.clear();
  }
  // A screenshot asked for interactively: once a full frame of the view is shown (while the
  // view moves, the first full one; no frame is cancelled meanwhile).
  if (!m_pending_screenshot.empty() && m_have_frame && m_frame_is_full && (m_delivered || !m_path->busy())) {
    take_screenshot(m_pending_screenshot);
    m_pending_screenshot.clear();
  }
  const auto t_swap = Clock::now();
  m_draw_ms = std::chrono::duration<double, std::milli>(t_swap - t_draw).count();
  m_window->swap(m_settings.vsync);
  m_swap_ms = ms_since(t_swap);
  ++m_presented;
  // ImGui hides a window that sizes itself in its first frame and fits a window to new content
  // a frame late: from the third frame with panels on after the first load ended (the scene's
  // lines in its panel), they are all on screen where they stay (tests click them from then on).
  if (m_settings.show_ui && !m_first_load_pending && ++m_ui_frames == 3)
    std::fprintf(stderr, "flashgs-viewer: UI ready %.0f ms after start (%.0f ms after the process started)\n",
                 ms_since_start(), ms_since_process_start());
}

void ViewerApp::log_popup_changes() {
  const bool open = m_ui && m_ui->popup_open();
  if (open == m_logged_popup_open) return;
  m_logged_popup_open = open;
  std::fprintf(stderr, "flashgs-viewer: popup %s\n", open ? "open" : "gone");
}

void ViewerApp::log_held_input() {
  // One line per frame while anything is held, each held button or key a token between
  // spaces (" mouse0 ", " key257 "): a test holds a button until it has seen two such frames.
  std::string held;
  for (int button = 0; button <= GLFW_MOUSE_BUTTON_LAST; ++button)
    if (m_window->mouse_down(button)) held += " mouse" + std::to_string(button);
  for (int key = GLFW_KEY_SPACE; key <= GLFW_KEY_LAST; ++key)
    if (m_window->key_down(key)) held += " key" + std::to_string(key);
  if (held.empty()) return;
  double x = 0, y = 0;
  m_window->cursor(&x, &y);
  // The pose too: a test dragging through X checks which way the view went.
  const Pose& p = m_controller.pose();
  const glm::vec3 f = p.rotation[2], r = p.rotation[0], pivot = m_controller.pivot();
  std::fprintf(stderr,
               "flashgs-viewer: frame %d held:%s at %.0f,%.0f | camera %.6f %.6f %.6f forward %.6f %.6f %.6f "
               "right %.6f %.6f %.6f pivot %.6f %.6f %.6f fov %.2f%s, HUD %.1f FPS\n",
               m_presented, held.c_str(), x, y, p.position.x, p.position.y, p.position.z, f.x, f.y, f.z, r.x, r.y, r.z,
               pivot.x, pivot.y, pivot.z, m_settings.fov_x_degrees,
               comparing()          ? " (comparing)"
               : m_export_job.busy() ? " (exporting)"
               : m_path->busy()      ? " (a frame is rendering)"
                                     : "",
               m_rendered_rate.rate(ms_since_start() / 1000.0));
}

void ViewerApp::log_option_changes() {
  // One line per change of the render options (the tests read which configuration is active).
  if (m_have_logged_options && m_settings.options == m_logged_options) return;
  m_logged_options = m_settings.options;
  m_have_logged_options = true;
  std::fprintf(stderr, "flashgs-viewer: options: %s\n", m_settings.options.label().c_str());
}

void ViewerApp::quit_now() {
  std::fprintf(stderr, "flashgs-viewer: quit (Esc / Ctrl+Q)\n");
  m_window->request_close();
}

// Esc first closes an open popup; with none open, it asks, and the next Esc quits. One press
// alone ended the session at once, also while a combo was open or an export ran.
void ViewerApp::handle_escape(bool keys_free) {
  if (m_ui && m_ui->close_popups()) {
    std::fprintf(stderr, "flashgs-viewer: popup closed (Esc)\n");
    return;
  }
  if (!keys_free) return;  // a text field's: ImGui leaves it
  if (m_quit_armed) return quit_now();
  m_quit_armed = true;
  m_status.clear();  // the request is logged again each time it is made
  set_notice(m_export.active() ? "press Esc again to quit (the path export in progress stops)"
                               : "press Esc again to quit, any other key to stay");
}

void ViewerApp::set_notice(const std::string& message) {
  if (message == m_status) return;  // a refusal repeated every frame is logged once
  m_status = message;
  std::fprintf(stderr, "flashgs-viewer: %s\n", message.c_str());
}

void ViewerApp::choose_render_size(int wanted_width, int wanted_height, int* width, int* height) {
  *width = wanted_width;
  *height = wanted_height;
  if (wanted_width == m_good_width && wanted_height == m_good_height) return;
  if (wanted_width != m_checked_width || wanted_height != m_checked_height) {
    m_checked_width = wanted_width;
    m_checked_height = wanted_height;
    m_checked_problem = frame_size_problem(wanted_width, wanted_height, m_path->texture_count(), m_max_texture_size,
                                           system_available_memory());
  }
  if (m_checked_problem.empty()) return;
  // Back to the last size that rendered; before the first frame, halves until it fits.
  int w = m_good_width, h = m_good_height;
  if (w <= 0 || h <= 0) {
    w = wanted_width;
    h = wanted_height;
    while ((w > 1 || h > 1) && !frame_size_problem(w, h, m_path->texture_count(), m_max_texture_size,
                                                   system_available_memory()).empty()) {
      w = std::max(1, w / 2);
      h = std::max(1, h / 2);
    }
  }
  m_settings.render_scale = m_good_scale;  // a typed scale that does not fit is not kept
  *width = w;
  *height = h;
  set_notice("render size " + size_text(wanted_width, wanted_height) + " refused: " + m_checked_problem +
             "; rendering at " + size_text(w, h));
}

void ViewerApp::render_failed(int width, int height, const std::string& why) {
  m_settings.render_scale = m_good_scale;
  m_settings.forced_width = m_settings.forced_height = 0;
  m_checked_width = width;  // not tried again at this size
  m_checked_height = height;
  m_checked_problem = why;
  const std::string back = m_good_width > 0 ? "back to " + size_text(m_good_width, m_good_height) : "nothing shown";
  set_notice("a " + size_text(width, height) + " frame failed: " + why + "; " + back);
  if (m_scripted) {  // a benchmark at another size would report the wrong numbers
    m_exit_code = 2;
    m_window->request_close();
  }
}

void ViewerApp::finish_script() {
  if (m_script->timed_any()) {
    std::printf("%s\n", m_script->frames_report(m_presenter->width(), m_presenter->height(), m_path->name()).c_str());
    std::printf("viewer render: last frame kv pairs %llu, visible %llu of %llu, backend total %.3f ms (project %.3f, emit %.3f, sort %.3f, ranges %.3f, blend %.3f)\n",
                static_cast<unsigned long long>(m_stats.kv_pairs), static_cast<unsigned long long>(m_stats.visible),
                static_cast<unsigned long long>(m_stats.gaussians), m_stats.times.total_ms, m_stats.times.project_ms,
                m_stats.times.emit_ms, m_stats.times.sort_ms, m_stats.times.ranges_ms, m_stats.times.blend_ms);
    std::printf("%s\n", m_script->split_report().c_str());
    const glm::vec3 p = m_controller.pose().position;
    std::printf("viewer camera: position %.6f %.6f %.6f\n", p.x, p.y, p.z);
  }
  if (m_args.compare && m_have_frame) {
    UiActions a;
    a.compare = true;
    apply_actions(a);
    m_compare_task.wait();  // the line below is the comparison's, however long it renders
    finish_comparison(/*at_once=*/true);
    if (m_compare.valid)
      std::printf("viewer compare: %s vs %s PSNR %.2f dB max abs %.6f\n", m_compare.right_label.c_str(),
                  m_compare.left_label.c_str(), m_compare.difference.psnr_db, m_compare.difference.max_abs);
  }
  if (!m_args.export_path.empty()) {
    if (m_keys.path().keys.size() >= 2) start_key_render(m_args.export_path);
    else start_path_export(m_args.export_path, m_args.export_frames);
    while (m_export.active() || m_encoding_video) export_step();
  }
  if (m_args.check_frame && m_have_frame) check_displayed_frame();
  if (!m_args.screenshot.empty()) take_screenshot(m_args.screenshot);
  std::fflush(stdout);
  if (!m_pending_overlay_shot.empty()) {
    m_close_after_shot = m_args.exit_after;  // taken while the next frame is drawn
  } else if (!m_args.window_screenshot.empty()) {
    // Taken at the end of the next frame, once the panels show this frame's statistics.
    m_pending_window_shot = m_args.window_screenshot;
    m_close_after_shot = m_args.exit_after;
  } else if (m_args.exit_after) {
    m_window->request_close();
  }
  m_scripted = false;  // interactive from here on (unless closing)
  m_settings.vsync = !m_args.no_vsync;
}

bool ViewerApp::open_window() {
  try {
    m_window = std::make_unique<Window>(m_args.window_width, m_args.window_height, "flashgs-viewer");
    m_presenter = std::make_unique<ImagePresenter>();
    m_presenter->init();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "flashgs-viewer: %s\n", e.what());
    return false;
  }
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &m_max_texture_size);
  std::fprintf(stderr, "flashgs-viewer: OpenGL %s, %s, textures up to %d pixels a side\n",
               reinterpret_cast<const char*>(glGetString(GL_VERSION)),
               reinterpret_cast<const char*>(glGetString(GL_RENDERER)), m_max_texture_size);
  float xscale = 1.0f, yscale = 1.0f;
  glfwGetWindowContentScale(m_window->handle(), &xscale, &yscale);
  int fb_w0 = 0, fb_h0 = 0;
  m_window->framebuffer_size(&fb_w0, &fb_h0);
  // X11 and Windows report a content scale of 2 on a 192-dpi screen with the framebuffer in
  // window units; macOS reports 2 and a framebuffer twice the window: the UI then needs no
  // extra scale, ImGui's points already being two pixels.
  m_ui_scale = std::max(1.0f, xscale / m_window->framebuffer_scale());
  std::fprintf(stderr, "flashgs-viewer: framebuffer %dx%d pixels, content scale %.2f, UI scale %.2f\n", fb_w0, fb_h0,
               xscale, m_ui_scale);
  // The panel layout is kept beside the settings (interactive runs only).
  m_ui = std::make_unique<ImGuiLayer>(*m_window, m_ui_scale, m_persist ? config_dir() + "/imgui.ini" : "");
  return true;
}

bool ViewerApp::begin_frame(int* fb_w, int* fb_h, float* dt) {
  // Waits for events only when nothing moves or renders every frame; a frame finished on the
  // worker wakes the loop (glfwPostEmptyEvent), and a load in progress redraws its bar.
  const bool idle = !m_scripted && !m_settings.continuous && !m_playing && !m_moving && m_arrived_textures == 0 &&
                    !m_stream.loading();  // a streamed set's chunks show as they arrive
  double wait_s = !idle ? 0.0 : m_loader.busy() || comparing() ? 0.1 : 0.5;  // progress redrawn
  const double settle_left_ms = kSettleMs - ms_since(m_last_motion);
  if (wait_s > 0 && settle_left_ms > 0) wait_s = std::min(wait_s, settle_left_ms / 1000.0 + 0.001);  // then the full frame
  m_window->poll(wait_s);
  m_frame_start = Clock::now();
  m_window->framebuffer_size(fb_w, fb_h);
  // Clamped so that a stall (a scene upload) does not turn into one huge step.
  *dt = m_scripted ? ScriptedRun::kFrameSeconds : std::min(0.5f, std::chrono::duration<float>(m_frame_start - m_last_frame_start).count());
  m_last_frame_start = m_frame_start;
  if (*fb_w > 0 && *fb_h > 0) return true;
  if (!m_scripted) glfwWaitEventsTimeout(0.1);  // minimised: nothing to draw into
  return false;
}

void ViewerApp::apply_script_step(NavigationInput& nav) {
  // While the key script runs it is the input; after it, the window's.
  if (!m_scripted || !m_script->has_input()) return;
  const ScriptFrame step = m_script->next_input();
  nav = step.nav;
  if (step.resize_width > 0) m_window->resize(step.resize_width, step.resize_height);
}

void ViewerApp::build_panels(int fb_w, int fb_h, UiActions& actions) {
  m_ui->begin_frame();  // every frame: the legend, help and hint show with the panels hidden too
  const UiModel model = panel_model(fb_w, fb_h);
  const ViewerSettings before = m_settings;
  // A screenshot with the overlay: this frame draws the legend's labels alone over the image
  // (no panels, no help, no status line), and the picture is taken once it is drawn.
  m_overlay_shot_frame = !m_pending_overlay_shot.empty();
  if (m_overlay_shot_frame) {
    draw_legend_labels(model, m_settings);
  } else {
    if (m_settings.show_ui)
      draw_panels(model, m_settings, actions, m_path_buffer, m_export_buffer, m_keys, m_key_fields);
    draw_overlays(model, m_settings);
    if (const std::string chosen = m_browser.draw(m_ui_scale); !chosen.empty()) actions.open_path = chosen;
  }
  keep_settings_valid(m_settings, before);
  if (const std::string chosen = m_dialog.take_choice(); !chosen.empty()) actions.open_path = chosen;
  if (!model.loading.empty() && !m_logged_load_progress) {
    m_logged_load_progress = true;
    std::fprintf(stderr, "flashgs-viewer: load progress shown %.0f ms after the load started, %.0f ms after start (%s)\n",
                 model.load.elapsed_s * 1000.0, ms_since_start(), model.loading.c_str());
  }
}

UiModel ViewerApp::panel_model(int fb_w, int fb_h) {
  UiModel model;
  model.frame_path = m_path->name();
  model.frame_path_note = m_path_note;
  model.backend = m_path_is_cpu ? Backend::cpu : Backend::cuda;
  model.scene_path = m_scene.path;
  const std::vector<ScenePart> drawn = drawn_parts();
  model.gaussians = scene_parts_size(drawn);
  model.sh_degree = drawn.empty() ? 0 : drawn.front().source->sh_degree;
  model.trained = m_scene.scene ? m_scene.scene->trained_kernel.kernel : SplatKernel::classic();
  model.trained_kernel = m_scene.scene ? kernel_summary(m_scene.scene->trained_kernel) : std::string();
  model.lod_gaussians = m_scene.lod_gaussians.empty() ? nullptr : &m_scene.lod_gaussians;
  model.lod_level = m_scene.lod_level;
  model.stream_summary = m_stream.summary();
  if (m_stream.active()) {
    model.stream_levels = m_stream.stats().drawn_per_level;
    model.stream_read_rates = &m_stream.read_rates().rates();
  }
  model.camera_count = static_cast<int>(m_scene.cameras.size());
  model.scene_note = m_scene.cameras_note;
  model.load_error = m_load_error;
  model.loading = m_loader.path();
  if (const LoadProgress* p = m_loader.progress()) {
    model.load.bytes_done = p->bytes_done;
    model.load.bytes_total = p->bytes_total;
    model.load.gaussians_done = p->gaussians_done;
    model.load.gaussians_total = p->gaussians_total;
    model.load.elapsed_s = m_loader.elapsed_seconds();
  }
  model.recent = &m_recent;
  model.current_camera = m_camera_index;
  model.view_description = m_controller.view_description(m_camera_index, m_last_camera.width, m_last_camera.height,
                                                         m_settings.fov_x_degrees);
  model.playing = m_playing;
  model.render_width = m_presenter->width();
  model.render_height = m_presenter->height();
  model.fps = m_rendered_rate.rate(ms_since_start() / 1000.0);
  model.last_frame_ms = m_last_frame_ms;
  model.rendering = background_busy();
  if (comparing()) model.comparing = m_comparing;
  model.compare_elapsed_s = m_compare_task.elapsed_seconds();
  model.compare_renders_done = m_compare_task.renders_done();
  model.compare_renders_total = m_compare_task.renders_total();
  model.stats = m_have_frame ? &m_stats : nullptr;
  model.history = &m_history;
  model.compare = &m_compare;
  model.heatmap_max = m_presenter->heatmap_max();
  model.tile_size = gm::kTileSize;
  model.debug_shown = m_debug_shown;
  model.debug_scale = m_debug_scale;
  model.compare_shown = comparison_shown();
  model.divider = m_divider.fraction();
  model.difference_factor = m_difference_factor;
  model.compare_problem = compare_sides_problem(m_settings.compare_left, m_settings.compare_right, m_settings.options,
                                                model.backend);
  model.export_done = m_export.done_frames();
  model.export_total = m_export.active() ? m_export.total_frames() : 0;
  model.dialog_tool = m_dialog.tool();
  model.dialog_open = m_dialog.busy() || m_browser.is_open();
  float legend_px[4];
  legend_rect(fb_w, fb_h, legend_px);
  for (int k = 0; k < 4; ++k) model.legend_rect_points[k] = legend_px[k] / m_window->framebuffer_scale();
  model.status = m_status;
  model.ui_scale = m_ui_scale;
  const glm::vec3 up = m_controller.world_up(), pos = m_controller.pose().position;
  for (int k = 0; k < 3; ++k) model.world_up[k] = up[k], model.position[k] = pos[k];
  return model;
}

bool ViewerApp::advance_camera(const NavigationInput& nav, float dt) {
  const bool steering = nav.forward || nav.back || nav.left || nav.right || nav.up || nav.down ||
                        nav.look_dx != 0.0f || nav.look_dy != 0.0f || nav.pan_dx != 0.0f || nav.pan_dy != 0.0f;
  if (m_playing && steering) m_playing = false;  // taking the controls stops the path
  if (m_keys.previewing() && steering) m_keys.stop_preview();
  if (preview_keys(dt)) return true;
  if (m_playing && m_camera_path && !m_camera_path->empty()) {
    m_path_t = m_camera_path->advance(m_path_t, dt, m_settings.path_seconds_per_camera);
    m_controller.set_pose(m_camera_path->pose_at(m_path_t));
    m_settings.fov_x_degrees = m_camera_path->fov_at(m_path_t);
  }
  bool moving = m_playing;
  if (!m_playing && m_controller.update(nav, dt, m_settings)) moving = true;
  if (m_scripted && m_args.path && m_camera_path && !m_camera_path->empty()) {
    const double t = m_script->path_time();
    m_controller.set_pose(m_camera_path->pose_at(t));
    m_settings.fov_x_degrees = m_camera_path->fov_at(t);
  }
  return moving;
}

void ViewerApp::record_frame_times(double frame_ms, double ui_ms, bool rendering) {
  if (m_delivered) m_history.push(m_path->renders_in_background() ? m_last_frame_ms : frame_ms, m_stats);
  if (rendering && !m_scripted && m_path->renders_in_background()) {  // scripted frames wait on purpose
    ++m_ui_frames_while_rendering;
    m_worst_ui_ms_while_rendering = std::max(m_worst_ui_ms_while_rendering, ui_ms);
    if (m_args.log_input && ui_ms >= 50.0)  // where a slow one went (tests print it on failure)
      std::fprintf(stderr, "flashgs-viewer: slow UI frame %d: %.1f ms (events + panels %.1f, frame request %.1f, comparison textures %.1f, draw %.1f, swap %.1f%s)\n",
                   m_presented, ui_ms, m_before_render_ms, m_render_call_ms, m_compare_show_ms, m_draw_ms, m_swap_ms,
                   m_delivered ? ", a frame uploaded" : "");
  }
  if (!m_scripted) return;
  FrameTimes times;
  times.frame_ms = frame_ms;
  times.before_render_ms = m_before_render_ms;
  times.render_call_ms = m_render_call_ms;
  times.draw_ms = m_draw_ms;
  times.swap_ms = m_swap_ms;
  m_script->frame_presented(times);
  if (m_script->open_then_now()) open_scene(m_args.then_open);  // must fail softly
  if (m_script->done()) finish_script();
}

int ViewerApp::run() {
  if (!open_window()) return 1;
  set_widget_place_logging(m_args.log_input);
  select_frame_path();
  if (!start_first_scene()) return 2;
  m_window->cursor(&m_last_cursor_x, &m_last_cursor_y);
  m_last_swap = Clock::now();
  while (!m_window->should_close()) run_one_frame();
  shut_down();
  return m_exit_code;
}

void ViewerApp::run_one_frame() {
  int fb_w = 0, fb_h = 0;
  float dt = 0;
  if (!begin_frame(&fb_w, &fb_h, &dt)) return;
  // A background frame or comparison in flight as this frame starts.
  const bool rendering = background_busy();
  const NavigationInput nav = take_input(fb_w, fb_h);
  advance_state(nav, dt);
  render_and_present(fb_w, fb_h);
  const auto swapped = Clock::now();
  const double frame_ms = std::chrono::duration<double, std::milli>(swapped - m_last_swap).count();
  m_last_swap = swapped;
  record_frame_times(frame_ms, ms_since(m_frame_start), rendering);
}

NavigationInput ViewerApp::take_input(int fb_w, int fb_h) {
  UiActions actions;
  NavigationInput nav;
  gather_input(nav, actions);
  apply_script_step(nav);
  build_panels(fb_w, fb_h, actions);
  if (m_args.log_input) {
    log_held_input();
    log_popup_changes();
  }
  apply_actions(actions);
  log_option_changes();
  return nav;
}

void ViewerApp::advance_state(const NavigationInput& nav, float dt) {
  finish_pending_load();
  if ((m_export.active() || m_export_job.busy()) && !m_scripted) export_step();  // polls the export's job
  m_moving = advance_camera(nav, dt);
  if (m_moving) m_last_motion = Clock::now();
}

void ViewerApp::render_and_present(int fb_w, int fb_h) {
  m_before_render_ms = ms_since(m_frame_start);
  request_frame(fb_w, fb_h, m_moving || ms_since(m_last_motion) < kSettleMs);
  collect_frame();
  show_debug_view();
  const auto t_compare = Clock::now();
  finish_comparison(/*at_once=*/false);
  m_compare_show_ms = ms_since(t_compare);
  draw_and_present(fb_w, fb_h);
}

void ViewerApp::shut_down() {
  save_settings();
  if (m_compare_task.busy()) {  // quitting stops it: its renders end at their next check, before the path goes
    m_compare_task.cancel();
    m_compare_task.wait();
    finish_comparison(/*at_once=*/true);  // logs the cancel
  }
  if (m_ui_frames_while_rendering > 0)
    std::fprintf(stderr, "flashgs-viewer: UI frames while a frame rendered in the background: %d, worst %.1f ms\n",
                 m_ui_frames_while_rendering, m_worst_ui_ms_while_rendering);
  if (m_loader.busy())  // its thread may be blocked in open(): closing does not wait for it
    std::fprintf(stderr, "flashgs-viewer: closing without waiting for the load of %s\n", m_loader.path().c_str());
}

}  // namespace flashgs::viewer
