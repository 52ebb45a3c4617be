// Camera construction from a pose, resizing with the field of view kept, and the rotation check.
#include "flashgs/camera.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "flashgs/error.h"

namespace flashgs {

Camera Camera::from_pose(int width, int height, float fx, float fy, const float camera_to_world[9],
                         const float centre[3]) {
  Camera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = fx;
  camera.fy = fy;
  // Pixel index i covers [i - 0.5, i + 0.5]; the optical axis hits the image centre.
  camera.cx = 0.5f * static_cast<float>(width) - 0.5f;
  camera.cy = 0.5f * static_cast<float>(height) - 0.5f;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) camera.rotation[r * 3 + c] = camera_to_world[c * 3 + r];
  for (int k = 0; k < 3; ++k) camera.position[k] = centre[k];
  return camera;
}

Camera Camera::resized(int new_width, int new_height) const {
  Camera camera = *this;
  const float sx = static_cast<float>(new_width) / static_cast<float>(width);
  const float sy = static_cast<float>(new_height) / static_cast<float>(height);
  camera.width = new_width;
  camera.height = new_height;
  camera.fx = fx * sx;
  camera.fy = fy * sy;
  camera.cx = (cx + 0.5f) * sx - 0.5f;
  camera.cy = (cy + 0.5f) * sy - 0.5f;
  return camera;
}

float Camera::horizontal_fov_degrees() const {
  return static_cast<float>(2.0 * std::atan(0.5 * width / fx) * 180.0 / M_PI);
}

void check_rotation(const double rows[9], const std::string& where) {
  // R^T R must be the identity and det R = +1 (a proper rotation).
  double worst = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      double dot = 0;
      for (int k = 0; k < 3; ++k) dot += rows[k * 3 + a] * rows[k * 3 + b];
      worst = std::max(worst, std::abs(dot - (a == b ? 1.0 : 0.0)));
    }
  const double det = rows[0] * (rows[4] * rows[8] - rows[5] * rows[7]) -
                     rows[1] * (rows[3] * rows[8] - rows[5] * rows[6]) +
                     rows[2] * (rows[3] * rows[7] - rows[4] * rows[6]);
  if (!(worst <= 1e-3) || det < 0)
    throw Error(where + ": rotation is not orthonormal (|R^T R - I| = " + std::to_string(worst) +
                ", det = " + std::to_string(det) + ")");
}

}  // namespace flashgs
