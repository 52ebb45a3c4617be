// ViewerArgs: the viewer's command line (scene, window, backend, render options, and the scripted mode).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "flashgs/lod_build.h"
#include "flashgs/lod_cut.h"
#include "flashgs/options.h"
#include "compare_mode.h"
#include "kernel_option.h"
#include "switch_flags.h"

namespace flashgs::viewer {

struct ViewerArgs {
  std::string scene;          // what locate_scene takes: a scene file or folder; empty: the demo scene
  std::string cameras;        // cameras.json; empty: the scene's own
  long generate_demo = 0;     // > 0: a procedural demo scene of this many Gaussians instead of a file
  int lod = -1;               // >= 0: this level of a SOG LOD set; -1: the finest that fits in memory
  int tile = 1;               // copies of the scene on a grid (large-scene benchmarks)
  bool stream = false;        // stream a LOD set by view instead of loading one level whole
  std::uint64_t stream_budget = 0;     // --budget: Gaussians drawn at most (0: the caps' only)
  float stream_max_error_px = kDefaultLodMaxErrorPx;  // --max-error-px
  bool lod_overlay = false;            // --lod-overlay: start with the level colours on
  // --stream of a scene file: its cached set's leaf cells and chunk files, in Gaussians.
  std::uint64_t lod_leaf_size = LodBuildOptions{}.leaf_gaussians;
  std::uint64_t lod_file_size = LodBuildOptions{}.file_gaussians;
  std::uint64_t host_memory_mb = 0, gpu_memory_mb = 0;  // --host-memory, --gpu-memory (0: no cap)
  int window_width = 1280, window_height = 800;
  int render_width = 0, render_height = 0;  // > 0: render at exactly this size
  float scale = 1.0f;
  std::string backend = "auto";  // auto | cpu | cuda
  int cpu_threads = 0;           // CPU renderer threads, 0: every core
  std::string up = "auto";       // auto | +x | -x | +y | -y | +z | -z
  bool flip_up = false;
  int camera = -1;               // snap to this camera at start
  float fov = 0;                 // > 0: horizontal field of view in degrees
  std::string algorithm = "flash";
  float tau = kDefaultTau;
  int sh_degree = 3;
  bool fp16_sh = false;          // the SH coefficients as half values (RenderOptions::fp16_sh)
  bool fp16_shape = false;       // rotation, scale and opacity as half values (RenderOptions::fp16_shape)
  bool fp16_blend = false;       // CUDA: the blend in half arithmetic (RenderOptions::fp16_blend)
  SwitchFlags switches;          // --no-<switch>: turned off over the saved settings
  KernelOption kernel;           // --kernel: auto (each scene's trained kernel) or one for every scene
  std::vector<float> background = {0, 0, 0};
  bool heatmap = false;
  bool orbit = false;            // start in orbit mode
  bool fly = false;              // start in fly mode (neither: orbit for object-sized scenes)
  bool grid = false, frustums = false, centres = false;
  std::string view = "colour";   // --view: flashgs/debug_view.h's names
  bool help_window = false;      // start with the shortcut table open
  std::string compare_view = "split";  // numbers | split | difference
  std::string compare_left = "baseline", compare_right = "current";  // compare_mode.h choice names
  int compare_rounds = kCompareRounds;
  float split_at = 0.5f;         // the divider, a fraction of the width
  bool screenshot_overlay = false;  // screenshots show the heat map as the window does
  std::string screenshot_dir;    // F12's folder; empty: the XDG pictures folder or the working directory
  std::string export_path;       // scripted: write the camera path as an image sequence into this folder
  int export_frames = 120;
  std::string camera_path;       // keyframed path file: loaded at start when it exists, the panel's save target
  bool no_ui = false;
  bool no_vsync = false;

  // Scripted mode.
  int frames = 0;                // render this many frames (then --screenshot, --exit)
  std::string keys;              // scripted key sequence, e.g. "W:0.5,D:0.2"
  bool path = false;             // play the camera path; with --frames K, K frames over one loop
  int warmup = 3;                // --path: frames rendered at the start before timing starts
  std::string screenshot;        // after the last scripted frame (PNG, EXR, PPM, PFM)
  std::string window_screenshot; // after the last scripted frame: the whole window, panels included
  bool exit_after = false;       // quit when the script is done
  std::string then_open;         // scripted: try to open this scene after the first frame (error-path test)
  bool check_frame = false;      // scripted: check the displayed texture against a host render
  bool compare = false;          // run compare mode once on the last frame and print it
  bool log_input = false;        // log each frame a mouse button is held (tests driving it through X)
  std::string render_gate;       // CPU path: each render waits until this file exists (tests hold a frame in flight)
  std::string load_gate;         // each background scene load waits until this file exists (tests hold a load in flight)

  bool scripted() const { return frames > 0 || !keys.empty() || path || !screenshot.empty() ||
                                  !window_screenshot.empty() || exit_after; }
};

// Parses argv; returns -1 to continue, or an exit code (help printed, or an error).
int parse_viewer_args(int argc, char** argv, ViewerArgs* args);

}  // namespace flashgs::viewer
