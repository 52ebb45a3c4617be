// Pinhole camera in the OpenCV convention (x right, y down, z forward), world-to-camera.
#pragma once

#include <string>

namespace flashgs {

struct Camera {
  int width = 0;
  int height = 0;
  float fx = 0, fy = 0;  // focal lengths in pixels
  float cx = 0, cy = 0;  // principal point in pixel-index coordinates (pixel centres are integers)
  // World-to-camera rotation, row-major. The view-space position of a world point p is
  // R * (p - position): subtracting the centre first keeps precision far from the origin,
  // where R * p + t would cancel two large numbers.
  float rotation[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  float position[3] = {0, 0, 0};  // camera centre in world space
  std::string name;

  // A camera with the principal point at the image centre.
  static Camera from_pose(int width, int height, float fx, float fy,
                          const float camera_to_world[9], const float centre[3]);
  // Same pose and field of view, another resolution (focal lengths scale with width/height).
  Camera resized(int new_width, int new_height) const;
  float horizontal_fov_degrees() const;
};

// Throws flashgs::Error starting with `where` unless the row-major 3x3 `rows` is a proper
// rotation (R^T R = I within 1e-3, det R = +1).
void check_rotation(const double rows[9], const std::string& where);

}  // namespace flashgs
