// Chunk culling: the per-frame test that proves none of a chunk's Gaussians can reach the
// image, so that preprocess classifies them from their centres without projecting them.
#pragma once

#include <math.h>

#include "flashgs/gaussian_math.h"
#include "flashgs/model_constants.h"
#include "pipeline.h"

namespace flashgs {
namespace cuda {

// True when no Gaussian of the chunk can touch the image, for the flash geometry `geo`
// (not the baseline). Proof: the footprint's half-width is at most
// s * sqrt(lambda_max + 0.3 + 0.32) + 1 pixels (dilation, the spread floor, ceil), with
// s^2 = max(9, 2 ln(o_max / tau)) the largest threshold and lambda_max <= (K sigma / z)^2,
// K >= ||J||_F over the clamped frustum directions. So the box misses the right edge when
// fx x - (16 tiles_x + pad - cx) z > s K sigma (z > 0), and likewise for the other edges;
// over the chunk's ball the left side is smallest at the centre minus |n| radius. Margins
// cover float rounding in the per-Gaussian projection. Gaussians behind the near plane are
// culled there whatever this says. Evaluated in double by one thread per chunk.
__device__ inline bool chunk_outside_view(const ChunkBound& b, const gm::CameraParams& cam,
                                          const gm::GeometryParams& geo) {
  if (!b.cullable) return false;
  const double d[3] = {double(b.cx) - cam.position[0], double(b.cy) - cam.position[1],
                       double(b.cz) - cam.position[2]};
  double v[3];
  for (int r = 0; r < 3; ++r)
    v[r] = double(cam.rotation[3 * r]) * d[0] + double(cam.rotation[3 * r + 1]) * d[1] +
           double(cam.rotation[3 * r + 2]) * d[2];
  const double radius = b.radius;
  const double v_len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  const double slack = 1e-4 * (v_len + radius);  // float rounding of the per-Gaussian view
  // Wholly behind the near plane: every Gaussian is culled there.
  if (v[2] + radius + slack < gm::kNearZ) return true;

  const double tau = geo.tau > 0.0f ? geo.tau : 1.0;
  const double o_max = b.max_opacity > 1.0f ? b.max_opacity : 1.0f;
  const double s = sqrt(fmax(9.0, 2.0 * log(o_max / tau)));
  // The Jacobian's directions are clamped to the frustum widened by kFrustumMargin.
  const double margin_x = model::kFrustumMargin * cam.width, margin_y = model::kFrustumMargin * cam.height;
  const double tx = fmax(fabs(double(cam.cx) + 0.5 + margin_x), fabs(cam.width - 0.5 - double(cam.cx) + margin_x)) / cam.fx;
  const double ty = fmax(fabs(double(cam.cy) + 0.5 + margin_y), fabs(cam.height - 0.5 - double(cam.cy) + margin_y)) / cam.fy;
  // 1.01: a quaternion within 1e-3 of unit norm makes a matrix of norm below 1.004.
  const double k = 1.01 * sqrt(double(cam.fx) * cam.fx * (1.0 + tx * tx) + double(cam.fy) * cam.fy * (1.0 + ty * ty));
  // A footprint that could overflow float (and be culled as degenerate) is left to project().
  const double z_min = fmax(v[2] - radius, double(gm::kNearZ));
  if (k * b.max_scale / z_min > 1e9) return false;

  const double reach = s * k * b.max_scale * 1.001;
  const double pad = 3.0 + 0.79 * s;  // pixels: ceil (1), dilation and floor (0.79 s), rounding (2)
  auto beyond = [&](double nx, double ny, double nz) {
    const double n_len = sqrt(nx * nx + ny * ny + nz * nz);
    return nx * v[0] + ny * v[1] + nz * v[2] - n_len * (radius + slack) > reach;
  };
  const double right = double(gm::kTileSize) * cam.tiles_x + pad - cam.cx;
  const double bottom = double(gm::kTileSize) * cam.tiles_y + pad - cam.cy;
  return beyond(cam.fx, 0.0, -right) || beyond(-cam.fx, 0.0, -(cam.cx + pad)) ||
         beyond(0.0, cam.fy, -bottom) || beyond(0.0, -cam.fy, -(cam.cy + pad));
}

}  // namespace cuda
}  // namespace flashgs
