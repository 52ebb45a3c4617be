// CameraPath: a smooth closed path through the scene's cameras (Catmull-Rom positions, slerped rotations).
#pragma once

#include <vector>

#include "camera_controller.h"
#include "flashgs/camera.h"

namespace flashgs::viewer {

class CameraPath {
 public:
  explicit CameraPath(const std::vector<Camera>& cameras);
  bool empty() const { return m_keys.empty(); }
  // t in [0, 1) covers the whole loop; passes through camera k at t = k / count. Any t is
  // accepted (wrapped into the loop; NaN and infinities give camera 0).
  Pose pose_at(double t) const;
  float fov_at(double t) const;
  std::size_t size() const { return m_keys.size(); }
  // The loop parameter `dt` seconds after `t` at `seconds_per_camera`, wrapped into [0, 1).
  // A duration that is not a positive finite number, or a non-finite dt, leaves t where it is.
  double advance(double t, double dt, double seconds_per_camera) const;

 private:
  struct Key {
    Pose pose;
    float fov;
  };
  // The key at or before loop parameter t and the fraction u in [0, 1) towards the next.
  void locate(double t, int* key, float* u) const;
  std::vector<Key> m_keys;
};

}  // namespace flashgs::viewer
