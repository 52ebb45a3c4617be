// Conversion of the public Camera / RenderOptions into the plain structs the kernels take.
#include "flashgs/frame_params.h"

namespace flashgs {

gm::CameraParams make_camera_params(const Camera& camera) {
  gm::CameraParams p{};
  for (int k = 0; k < 9; ++k) p.rotation[k] = camera.rotation[k];
  for (int k = 0; k < 3; ++k) p.position[k] = camera.position[k];
  p.fx = camera.fx;
  p.fy = camera.fy;
  p.cx = camera.cx;
  p.cy = camera.cy;
  p.width = camera.width;
  p.height = camera.height;
  p.tiles_x = (camera.width + gm::kTileSize - 1) / gm::kTileSize;
  p.tiles_y = (camera.height + gm::kTileSize - 1) / gm::kTileSize;
  gm::frustum_limits(p, p.frustum);
  return p;
}

gm::GeometryParams make_geometry_params(const RenderOptions& options) {
  gm::GeometryParams g{};
  g.baseline = options.is_baseline();
  g.opacity_radius = options.uses_opacity_radius();
  g.tight_bbox = options.uses_tight_bbox();
  g.tau = options.tau;
  g.dilation = options.kernel.dilation();
  g.compensate_opacity = options.kernel.compensates_opacity();
  return g;
}

}  // namespace flashgs
