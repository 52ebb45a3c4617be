// Command-line parsing for flashgs-viewer (CLI11).
#include "viewer_args.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <CLI/CLI.hpp>

#include "compare_mode.h"
#include "finite_option.h"
#include "flashgs/debug_view.h"
#include "flashgs/error.h"
#include "flashgs/io.h"
#include "flashgs/parse.h"
#include "viewer_settings.h"

namespace flashgs::viewer {
namespace {

// A finite number in `range` (app/common/finite_option.h).
CLI::Validator finite_in(ValueRange range) { return flashgs::finite_in(range.min, range.max); }

constexpr int kMaxSide = 32768;

// "WxH" with both sides in 1..kMaxSide (the parser shared with the CLI); a ValidationError
// naming `option` otherwise.
void parse_size(const std::string& option, const std::string& text, int* w, int* h) {
  try {
    const Resolution size = parse_resolution(text, kMaxSide);
    *w = size.width;
    *h = size.height;
  } catch (const Error& e) {
    throw CLI::ValidationError(option, e.what());
  }
}

}  // namespace

int parse_viewer_args(int argc, char** argv, ViewerArgs* a) {
  CLI::App app{"flashgs-viewer: fly through a 3D Gaussian Splatting scene (FlashGS renderer, CUDA or CPU)"};
  std::string size, render_size;
  app.add_option("scene", a->scene, kSceneArgumentHelp);
  app.add_option("--cameras", a->cameras, "cameras.json (default: the scene's own)");
  CLI::Option* lod = app.add_option("--lod", a->lod, kLodOptionHelp)->check(CLI::NonNegativeNumber);
  app.add_option("--generate-demo", a->generate_demo, "use a procedural demo scene of N Gaussians instead of a file")
      ->check(CLI::Range(1L, 200000000L))
      ->excludes(lod);
  app.add_option("--tile", a->tile, "render K copies of the scene on a grid (large-scene benchmarks)")
      ->check(CLI::Range(1, 1024));
  app.add_flag("--stream", a->stream,
               "stream a LOD set by view (lod-meta.json of PlayCanvas or of `flashgs lod build`): the detail the view needs, "
               "within --budget and the memory caps")
      ->excludes(lod);
  app.add_option("--budget", a->stream_budget, "--stream: Gaussians drawn at most (default: what the caps allow)")
      ->check(whole_number());
  app.add_option("--max-error-px", a->stream_max_error_px, "--stream: refine a cell while its error in pixels is larger")
      ->check(finite_in(kStreamErrorRange));
  app.add_option("--lod-leaf-size", a->lod_leaf_size,
                 "--stream of a scene file (not a LOD set): Gaussians of a leaf cell of the set built for it, about")
      ->check(whole_number())
      ->check(CLI::Range(1, 1 << 26));
  app.add_option("--lod-file-size", a->lod_file_size,
                 "--stream of a scene file: Gaussians per chunk file of the set built for it, at most")
      ->check(whole_number())
      ->check(CLI::Range(1, 1 << 28));
  app.add_flag("--lod-overlay", a->lod_overlay, "--stream: start with each Gaussian in its level's colour (Scene panel)");
  app.add_option("--host-memory", a->host_memory_mb, "--stream: MiB of host memory for chunks and drawn scenes (default: no cap)")
      ->check(whole_number());
  app.add_option("--gpu-memory", a->gpu_memory_mb, "--stream: MiB of GPU memory for the drawn scene (default: no cap)")
      ->check(whole_number());
  app.add_option("--size", size, "window size WxH in screen points (default 1280x800)");
  app.add_option("--render-size", render_size, "render at exactly WxH whatever the window size");
  app.add_option("--scale", a->scale, "render resolution = framebuffer size * scale")->check(finite_in(kRenderScaleRange));
  app.add_option("--backend", a->backend, "auto, cpu or cuda")->check(CLI::IsMember({"auto", "cpu", "cuda"}));
  app.add_option("--threads", a->cpu_threads, "CPU renderer threads (0: every core; fewer leave cores to other work)")
      ->check(CLI::Range(0, 1024));
  app.add_option("--up", a->up, "world up axis: auto (from the cameras), +x, -x, +y, -y, +z, -z")
      ->check(CLI::IsMember({"auto", "+x", "-x", "+y", "-y", "+z", "-z"}));
  app.add_flag("--flip-up", a->flip_up, "invert the world up axis (scenes that load upside down)");
  app.add_option("--camera,-c", a->camera, "start at this camera of cameras.json")
      ->check(CLI::Validator([](std::string& text) {
        return text.empty() || text[0] == '-' ? "\"" + text + "\" is not a camera index (0 or more)" : std::string();
      }, "INDEX >= 0"));
  app.add_option("--fov", a->fov, "horizontal field of view in degrees")->check(finite_in(kFovRange));
  app.add_option("--algorithm,-a", a->algorithm, "flash or baseline")->check(CLI::IsMember({"flash", "baseline"}));
  a->switches.add_to(&app);
  a->kernel.add_to(&app);
  app.add_option("--tau", a->tau, "alpha threshold of the opacity-aware extent")->check(finite_in(kTauRange));
  app.add_option("--sh-degree", a->sh_degree, "use at most this many SH bands")->check(CLI::Range(0, kMaxShDegree));
  app.add_flag("--fp16-sh", a->fp16_sh, "use the SH coefficients as half values (not exact)");
  app.add_flag("--fp16-shape", a->fp16_shape, "use each Gaussian's rotation, scale and opacity as half values (not exact)");
  app.add_flag("--fp16-blend", a->fp16_blend, "CUDA: blend in half arithmetic (not exact; the CPU renders exactly)");
  app.add_option("--background", a->background, "background colour r,g,b in [0, 1]")
      ->delimiter(',')
      ->expected(3)
      ->check(finite_in(kBackgroundRange));
  app.add_flag("--heatmap", a->heatmap, "start with the per-tile pair-count overlay on");
  auto* orbit = app.add_flag("--orbit", a->orbit, "start in orbit mode (default: orbit for object-sized scenes, else fly)");
  app.add_flag("--fly", a->fly, "start in fly mode")->excludes(orbit);
  app.add_flag("--grid", a->grid, "start with the ground grid and axes shown (G)");
  app.add_flag("--centres", a->centres, "start with the Gaussians' centres drawn as dots (a debug view)");
  app.add_option("--view", a->view,
                 std::string("start with this view (V): ") + kFrameViewChoices +
                     " (depth: the blended depth, count: Gaussians blended per pixel)")
      ->check([](const std::string& text) {
        FrameView v;
        return parse_frame_view(text, &v) ? std::string() : "'" + text + "' is not one of " + kFrameViewChoices;
      });
  app.add_flag("--frustums", a->frustums, "start with the training cameras drawn as frustums");
  app.add_flag("--help-window", a->help_window, "start with the shortcut table open (F1)");
  app.add_option("--compare-view", a->compare_view, "what a comparison shows: numbers, split or difference")
      ->check(CLI::IsMember({"numbers", "split", "difference"}));
  const auto choice = CLI::Validator([](std::string& text) {
    if (compare_choice_from_name(text) >= 0) return std::string();
    std::string names;
    for (int c = 0; c < compare_choice_count(); ++c) names += (c ? ", " : "") + compare_choice_name(c);
    return "\"" + text + "\" is not a configuration (" + names + ")";
  }, "CONFIG");
  app.add_option("--compare-left", a->compare_left, "the comparison's left side (default baseline)")->check(choice);
  app.add_option("--compare-right", a->compare_right, "the comparison's right side (default current)")->check(choice);
  app.add_option("--compare-rounds", a->compare_rounds,
                 "timed rounds of a comparison, each rendering both sides after one warm-up each")
      ->check(CLI::Range(1, 100));
  app.add_option("--split-at", a->split_at, "the split view's divider, a fraction of the width")
      ->check(finite_in(ValueRange{0.02f, 0.98f}));
  app.add_flag("--screenshot-overlay", a->screenshot_overlay,
               "screenshots include the heat map (at the window's size) as the window shows it");
  app.add_option("--screenshot-dir", a->screenshot_dir,
                 "folder for F12's timestamped screenshots (default: the XDG pictures folder, else the working directory)");
  app.add_option("--export-path", a->export_path,
                 "scripted: write the camera path as an image sequence (frame_00000.png, ...) into this folder, "
                 "and path.mp4 when ffmpeg is on PATH");
  app.add_option("--camera-path", a->camera_path,
                 "a keyframed camera path (JSON, or nerfstudio's camera_path.json): loaded at start when it exists, "
                 "and where the panel saves; with it, --export-path renders its frames at its size and fps");
  app.add_option("--export-frames", a->export_frames, "frames of --export-path (default 120)")->check(CLI::Range(1, 100000));
  app.add_flag("--no-ui", a->no_ui, "hide the panels (Tab toggles them)");
  app.add_flag("--no-vsync", a->no_vsync, "present without waiting for vertical sync");
  app.add_option("--frames", a->frames, "scripted: render this many frames")->check(CLI::Range(0, 10000000));
  app.add_option("--keys", a->keys,
                 "scripted: keys held for seconds of simulated time (60 frames per second), e.g. "
                 "\"W:0.5,D+SHIFT:0.2,MOUSE:120:-40,RESIZE:800:450,WAIT:0.1\"");
  app.add_flag("--path", a->path, "scripted: play a smooth path through the scene's cameras and report frame times");
  app.add_option("--warmup", a->warmup, "scripted: untimed frames before the timed ones")->check(CLI::Range(0, 10000));
  app.add_option("--screenshot", a->screenshot, "scripted: save the rendered image (no UI) after the last frame");
  app.add_option("--window-screenshot", a->window_screenshot,
                 "scripted: save the whole window, panels included, after the last frame");
  app.add_flag("--exit", a->exit_after, "scripted: quit when done");
  app.add_option("--then-open", a->then_open,
                 "scripted: open this scene after the first frame (a failure must keep the current scene)");
  app.add_flag("--check-frame", a->check_frame,
               "scripted: compare the displayed texture with the backend's host image of the same view "
               "(exit 4 when they differ)");
  app.add_flag("--compare", a->compare, "scripted: compare the last frame with the baseline and print PSNR");
  app.add_flag("--log-input", a->log_input,
               "log every frame in which a mouse button is held, and where the clickable widgets are (for tests that click through X)");
  app.add_option("--render-gate", a->render_gate,
                 "CPU path: each render waits until this file exists (for tests that act while a frame renders)");
  app.add_option("--load-gate", a->load_gate,
                 "each scene load beside the window waits until this file exists before it reads anything "
                 "(for tests that act while a scene loads)");
  try {
    app.parse(argc, argv);
    if (!size.empty()) parse_size("--size", size, &a->window_width, &a->window_height);
    if (!render_size.empty()) parse_size("--render-size", render_size, &a->render_width, &a->render_height);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return -1;
}

}  // namespace flashgs::viewer
