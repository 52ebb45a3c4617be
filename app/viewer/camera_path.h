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
  // t in [0, 1) covers the whole loop; passes through camera k at t = k / count.
  Pose pose_at(double t) const;
  float fov_at(double t) const;
  std::size_t size() const { return m_keys.size(); }

 private:
  struct Key {
    Pose pose;
    float fov;
  };
  std::vector<Key> m_keys;
};

}  // namespace flashgs::viewer
