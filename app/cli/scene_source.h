// Where the CLI's scene, cameras and renderer come from (shared by every subcommand).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "flashgs/camera.h"
#include "flashgs/io.h"
#include "flashgs/options.h"
#include "flashgs/scene.h"
#include "flashgs/scene_formats.h"
#include "kernel_option.h"
#include "scene_level.h"
#include "switch_flags.h"

namespace flashgs::cli {

struct SceneArgs {
  std::string scene_path;    // a PLY or a scene folder; not given: the demo scene
  std::string cameras_path;  // not given: the scene's own cameras.json
  int lod = -1;              // level of a SOG LOD set; -1: the finest that fits in memory
  std::string spz_axes = "niantic";
  void add_to(CLI::App* command);
  // What the scene files are read with (--spz-axes).
  SceneReadOptions read_options() const;
  // The PLY and cameras.json to use (see locate_scene); throws flashgs::Error for a path given
  // empty, or one that names no usable scene.
  SceneLocation locate() const;
  std::string resolved_scene() const { return locate().ply; }
  std::string resolved_cameras() const { return locate().cameras; }

 private:
  CLI::Option* m_scene_option = nullptr;
  CLI::Option* m_cameras_option = nullptr;
};

// Loads the scene, printing what the loader dropped to stderr.
std::shared_ptr<const Scene> load_scene_verbose(const std::string& path, int lod = -1,
                                               const SceneReadOptions& options = {});
// The --spz-axes option's help, shared by every command that reads scenes.
inline constexpr const char kSpzAxesHelp[] =
    "axes of SPZ files: niantic (right-up-back, as Niantic's spz library writes) or none (PLY's axes unchanged, "
    "as some converters wrote)";
// A SOG LOD set's levels, one line each (Gaussians, SH degree, memory), for `flashgs info`;
// empty for any other scene.
std::string describe_lod_levels(const std::string& path);

struct RenderArgs {
  std::string algorithm = "flash";
  SwitchFlags switches;
  KernelOption kernel;
  float tau = kDefaultTau;
  std::vector<float> background = {0, 0, 0};
  int sh_degree = 3;
  bool fp16_sh = false;
  bool fp16_shape = false;
  bool fp16_blend = false;
  std::string backend = "auto";
  void add_to(CLI::App* command);
  // The options these flags give for `scene` (whose trained kernel --kernel auto takes).
  RenderOptions options(const Scene& scene) const;
};

// The largest |coordinate| --eye, --look-at and --up accept (float range).
constexpr double kMaxCoordinate = 3.4e38;

struct CameraArgs {
  int index = 0;
  std::string resolution;  // "WxH"; empty: the camera's own
  // An explicit camera instead of cameras.json: eye and target given.
  std::vector<float> eye, look_at, up = {0, -1, 0};
  float fov_degrees = 60.0f;
  void add_to(CLI::App* command);
  bool is_explicit() const { return !eye.empty(); }
  // The explicit camera, or camera `index` of the file at `cameras_path` (read only then).
  Camera select(const std::string& cameras_path) const;
};

}  // namespace flashgs::cli
