// Scene loading for the viewer: PLY + cameras.json, the framing (centre, extent, up) and procedural stand-ins.
#include "scene_state.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "flashgs/error.h"
#include "flashgs/generators.h"
#include "flashgs/io.h"

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

std::string file_type_problem(const std::filesystem::file_status& status) {
  using std::filesystem::file_type;
  switch (status.type()) {
    case file_type::regular: return "";
    case file_type::not_found: return "no such file";
    case file_type::directory: return "a folder, not a file";
    case file_type::fifo: return "a FIFO (named pipe), not a regular file";
    case file_type::socket: return "a socket, not a regular file";
    case file_type::block:
    case file_type::character: return "a device, not a regular file";
    default: return "not a regular file";
  }
}

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

LoadedScene load_scene(const std::string& ply_path, const std::string& cameras_path) {
  LoadedScene s;
  s.path = ply_path;
  const auto status = std::filesystem::status(ply_path);
  if (std::filesystem::is_directory(status)) {
    // A folder is accepted when it holds point_cloud.ply (the layout of the shared scenes).
    const auto inner = std::filesystem::path(ply_path) / "point_cloud.ply";
    if (!std::filesystem::exists(inner)) throw Error(ply_path + ": a folder without point_cloud.ply");
    return load_scene(inner.string(), cameras_path);
  }
  // Checked before opening: opening a FIFO (or a device) blocks until a writer appears.
  if (const std::string problem = file_type_problem(status); !problem.empty()) throw Error(ply_path + ": " + problem);
  s.scene = std::make_shared<const Scene>(load_ply(ply_path, &s.report));
  if (s.scene->size() == 0) throw Error(ply_path + ": the file holds no usable Gaussians");
  const std::string cameras = cameras_path.empty()
                                  ? (std::filesystem::path(ply_path).parent_path() / "cameras.json").string()
                                  : cameras_path;
  const auto cameras_status = std::filesystem::status(cameras);
  if (!std::filesystem::exists(cameras_status)) {
    s.cameras_note = cameras + ": not found (free navigation only)";
  } else if (const std::string problem = file_type_problem(cameras_status); !problem.empty()) {
    s.cameras_note = cameras + ": " + problem + " (free navigation only)";
  } else {
    try {
      s.cameras = load_cameras(cameras);
    } catch (const Error& e) {
      s.cameras_note = e.what();
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
