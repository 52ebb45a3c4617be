// LoadedScene: a scene with its cameras and the framing the viewer derives from them; loading never leaves a half-made scene.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "flashgs/camera.h"
#include "flashgs/load_progress.h"
#include "flashgs/scene.h"

namespace flashgs::viewer {

struct LoadedScene {
  std::string path;                     // the PLY (or a description for generated scenes)
  std::shared_ptr<const Scene> scene;
  std::vector<Camera> cameras;          // may be empty
  LoadReport report;
  std::string cameras_note;             // why there are no cameras, if so
  std::string refused_option;           // a start option the load could not apply (--tile), one line
  glm::vec3 centre{0.0f};               // orbit pivot / default look-at
  float extent = 1.0f;                  // typical size, sets navigation speeds
  glm::vec3 up{0.0f, -1.0f, 0.0f};      // guessed world up
  // A SOG LOD set: the Gaussians of each level (0 the finest) and the level loaded.
  std::vector<std::size_t> lod_gaussians;
  int lod_level = -1;
};

// Loads the scene at `path` (a PLY, a folder holding point_cloud.ply or a 3DGS training
// output: flashgs::locate_scene) and its cameras.json (or `cameras_path`). Throws
// flashgs::Error naming the file and the problem, before opening anything that is not a
// regular file (a FIFO would block); a missing, broken or irregular cameras.json is not fatal
// (noted).
// `progress` (may be null) gets the file's size at once and whatever the reader reports.
// A SOG LOD set loads level `lod_level` (-1: the finest that fits in host memory;
// kCoarsestLodLevel: its coarsest, the view a streamed set starts from).
constexpr int kCoarsestLodLevel = -2;
LoadedScene load_scene(const std::string& path, const std::string& cameras_path = "", LoadProgress* progress = nullptr,
                       int lod_level = -1);
// The procedural demo scene (`count` Gaussians) with orbit cameras, for runs where no file can travel.
LoadedScene generate_demo_scene(std::size_t count);
// `copies` copies of a loaded scene on a grid (large-scene benchmarks); cameras kept.
LoadedScene tile_loaded_scene(const LoadedScene& source, int copies);

// Guesses world up from the cameras (their mean "up" = -y axis), snapped to a coordinate axis
// when close; -y (the COLMAP habit) without cameras.
glm::vec3 guess_up(const std::vector<Camera>& cameras);

}  // namespace flashgs::viewer
