// A keyframed camera path (poses with times, eased between), as the viewer authors it and `flashgs render --path` renders it; read and written as JSON, nerfstudio's camera_path.json read too.
#pragma once

#include <string>
#include <vector>

#include "flashgs/camera.h"

namespace flashgs {

struct Keyframe {
  double time_s = 0;                 // seconds from the path's start
  float position[3] = {0, 0, 0};     // camera centre in world space
  float camera_to_world[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major, OpenCV axes (x right, y down, z forward)
  float fov_x_degrees = 60.0f;       // horizontal field of view

  static Keyframe from_camera(const Camera& camera, double time_s);
};

// Between the keys: linear keeps the keys' own timing; ease_in_out starts and ends the whole
// path at rest (smoothstep on its time).
enum class PathEasing { linear, ease_in_out };
const char* easing_name(PathEasing easing);  // "linear", "ease_in_out"

struct KeyframePath {
  std::vector<Keyframe> keys;  // in time order (sort_keys)
  PathEasing easing = PathEasing::ease_in_out;
  int fps = 30;
  int width = 1920, height = 1080;  // the render's size

  double duration_s() const { return keys.empty() ? 0.0 : keys.back().time_s - keys.front().time_s; }
  // Frames of a render at `fps`: one per 1/fps of the duration, both ends included.
  int frame_count() const;
  // The time of frame `index` (keys.front().time_s + index / fps).
  double frame_time(int index) const;
  // The camera at `time_s` (clamped to the path) at width x height: positions on a
  // Catmull-Rom curve through the keys, rotations slerped, the FOV linear between keys.
  // At a key's time it is that key's pose. Needs at least one key.
  Camera camera_at(double time_s, int width, int height) const;
  // Keeps the keys in time order after a key's time changed (stable: equal times keep their order).
  void sort_keys();
};

// Limits of a path file's values (what a person would author; anything beyond is a mistake).
inline constexpr int kMaxPathFps = 240;
inline constexpr int kMaxPathSide = 16384;
inline constexpr std::size_t kMaxKeyframes = 100000;

// Reads a path file: ours ("flashgs camera path") or nerfstudio's camera_path.json (its
// "camera_path" frames become keys 1/fps apart, OpenGL axes turned into OpenCV's, its vertical
// FOV into a horizontal one). Throws flashgs::Error naming `path` and the problem.
KeyframePath read_camera_path(const std::string& path);
KeyframePath parse_camera_path(const std::string& json_text, const std::string& name);
// Writes `path_data` to `path` (atomically: a temporary renamed once written).
void write_camera_path(const KeyframePath& path_data, const std::string& path);

}  // namespace flashgs
