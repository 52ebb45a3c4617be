// Scene loading for the viewer: PLY + cameras.json, the framing (centre, extent, up) and procedural stand-ins.
#include "scene_state.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "flashgs/frame_memory.h"
#include "flashgs/generators.h"
#include "flashgs/io.h"
#include "flashgs/scene_formats.h"

namespace flashgs::viewer {
namespace {

// Centre and extent from the Gaussians: the 5-95 % range per axis, so a few far-flung
// floaters (common in trained scenes) do not set the scale.
void frame_from_points(const Scene& scene, glm::vec3* centre, float* extent) {
  const std::size_t n = scene.size();
  if (n == 0) return;
  const std::size_t stride = std::max<std::size_t>(1, n / 20000);
  glm::vec3 lo, hi;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<float> v;
    for (std::size_t i = 0; i < n; i += stride) v.push_back(scene.positions[i * 3 + axis]);
    const std::size_t a = v.size() * 5 / 100, b = std::min(v.size() - 1, v.size() * 95 / 100);
    std::nth_element(v.begin(), v.begin() + a, v.end());
    lo[axis] = v[a];
    std::nth_element(v.begin(), v.begin() + b, v.end());
    hi[axis] = v[b];
  }
  *centre = 0.5f * (lo + hi);
  *extent = std::max(0.5f * glm::length(hi - lo), 1e-3f);
}

void frame_scene(LoadedScene& s) {
  frame_from_points(*s.scene, &s.centre, &s.extent);
  s.up = guess_up(s.cameras);
}

}  // namespace

glm::vec3 guess_up(const std::vector<Camera>& cameras) {
  glm::vec3 sum(0.0f);
  for (const Camera& c : cameras) sum -= glm::vec3(c.rotation[3], c.rotation[4], c.rotation[5]);  // row 1 = camera y (down)
  if (cameras.empty() || !(glm::length(sum) > 1e-6f)) return glm::vec3(0.0f, -1.0f, 0.0f);
  glm::vec3 up = glm::normalize(sum);
  for (int axis = 0; axis < 3; ++axis)
    if (std::abs(up[axis]) > 0.9f) {
      glm::vec3 snapped(0.0f);
      snapped[axis] = up[axis] > 0.0f ? 1.0f : -1.0f;
      return snapped;
    }
  return up;
}

LoadedScene load_scene(const std::string& path, const std::string& cameras_path, LoadProgress* progress,
                       int lod_level) {
  // A PLY, a folder holding point_cloud.ply or a 3DGS training output (the library's rule, as
  // in the command-line tool); FIFOs and devices are refused before anything is opened.
  const SceneLocation location = locate_scene(path);
  LoadedScene s;
  s.path = location.ply;
  if (progress && progress->bytes_total == 0) {  // the size at least, before the reader says more
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(location.ply, ec);
    if (!ec) progress->bytes_total = bytes;
  }
  if (is_sog_lod_set(location.ply)) {
    const SogLodSet set = describe_sog_lod(location.ply);
    const int level = lod_level >= 0                  ? lod_level
                      : lod_level == kCoarsestLodLevel ? static_cast<int>(set.levels.size()) - 1
                                                       : choose_sog_lod_level(set, available_host_memory().bytes);
    if (level >= static_cast<int>(set.levels.size()))
      throw Error(location.ply + ": LOD level " + std::to_string(level) + " asked for, the set has levels 0.." +
                  std::to_string(set.levels.size() - 1));
    for (const SogLodLevel& l : set.levels) s.lod_gaussians.push_back(l.gaussians);
    s.lod_level = level;
    s.scene = std::make_shared<const Scene>(read_sog_lod(location.ply, level, &s.report, progress));
  } else {
    if (lod_level >= 0) throw Error(location.ply + ": not a SOG LOD set, it has no levels to choose from");
    s.scene = std::make_shared<const Scene>(load_scene_file(location.ply, &s.report, progress));
  }
  if (s.scene->size() == 0) throw Error(location.ply + ": the file holds no usable Gaussians");
  const std::string cameras = cameras_path.empty() ? location.cameras : cameras_path;
  if (!std::filesystem::exists(std::filesystem::symlink_status(cameras))) {
    s.cameras_note = cameras + ": not found (free navigation only)";
  } else {
    try {
      s.cameras = load_cameras(cameras);  // refuses a FIFO or device without opening it
    } catch (const Error& e) {
      s.cameras_note = std::string(e.what()) + " (free navigation only)";
      s.cameras.clear();
    }
  }
  frame_scene(s);
  return s;
}

LoadedScene generate_demo_scene(std::size_t count) {
  LoadedScene s;
  s.path = "generated demo scene (" + std::to_string(count) + " Gaussians)";
  s.scene = std::make_shared<const Scene>(make_demo_scene(count));
  frame_from_points(*s.scene, &s.centre, &s.extent);
  // The demo scene is y-up; 24 orbit views around it at 1920x1080, 60 degrees.
  const float target[3] = {s.centre.x, s.centre.y, s.centre.z};
  const float up[3] = {0.0f, 1.0f, 0.0f};
  s.cameras = make_orbit_cameras(target, up, 2.2f * s.extent, 0.8f * s.extent, 24, 1920, 1080, 60.0f);
  s.up = guess_up(s.cameras);
  return s;
}

LoadedScene tile_loaded_scene(const LoadedScene& source, int copies) {
  LoadedScene s = source;
  s.scene = std::make_shared<const Scene>(tile_scene(*source.scene, copies));
  s.path = source.path + " x" + std::to_string(copies);
  // The cameras pushed back from the grid centre as `flashgs generate tile` does, so that the
  // whole grid is in view and every copy costs work.
  float lo[3], hi[3];
  scene_bounds(*source.scene, lo, hi);
  const float side = std::ceil(std::sqrt(static_cast<float>(copies)));
  for (Camera& camera : s.cameras)
    for (int k = 0; k < 3; ++k) {
      const float centre = 0.5f * (lo[k] + hi[k]);
      camera.position[k] = centre + (camera.position[k] - centre) * side;
    }
  frame_from_points(*s.scene, &s.centre, &s.extent);
  return s;
}

}  // namespace flashgs::viewer
