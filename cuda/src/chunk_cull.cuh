// Chunk culling: the per-frame test that proves none of a chunk's Gaussians can reach the
// image, so that preprocess classifies them from their centres without projecting them.
#pragma once

#include <math.h>

#include "flashgs/gaussian_math.h"
#include "pipeline.h"

namespace flashgs {
namespace cuda {

// Whether any Gaussian of the chunk can touch the image (ChunkCullFrame says why), and if
// not, whether their cull reasons are known without reading them. Float, one thread per
// chunk: the per-frame constants come from the host.
__device__ __forceinline__ ChunkVerdict chunk_verdict(const ChunkBound& b, const gm::CameraParams& cam,
                                                      const gm::GeometryParams& geo, const ChunkCullFrame& frame) {
  if (!b.cullable) return kChunkProject;
  const float d[3] = {b.cx - cam.position[0], b.cy - cam.position[1], b.cz - cam.position[2]};
  float v[3];
  for (int r = 0; r < 3; ++r)
    v[r] = cam.rotation[3 * r] * d[0] + cam.rotation[3 * r + 1] * d[1] + cam.rotation[3 * r + 2] * d[2];
  // Rounding of this view and of each Gaussian's (|d|_1 bounds |d|).
  const float slack = 1e-4f * (fabsf(d[0]) + fabsf(d[1]) + fabsf(d[2]) + b.radius);
  const float radius = b.radius + slack;
  if (v[2] + radius < gm::kNearZ) return kChunkAllNear;  // every centre behind the near plane
  // A footprint that could overflow float (and be culled as degenerate) is left to project().
  const float z_min = fmaxf(v[2] - radius, gm::kNearZ);
  if (!(frame.jacobian_bound * b.max_scale <= 1e9f * z_min)) return kChunkProject;
  const float reach = frame.reach_per_sigma * b.max_scale;
  bool outside = false;
  for (int k = 0; k < 4; ++k) {
    const float* n = frame.edge_normal[k];
    outside |= n[0] * v[0] + n[1] * v[1] + n[2] * v[2] - frame.edge_normal_length[k] * radius > reach;
  }
  if (!outside) return kChunkProject;
  // Every centre in front of the near plane and none culled for its opacity: all off screen.
  const bool none_low = !geo.opacity_radius || b.min_opacity >= geo.tau;
  return v[2] - radius > gm::kNearZ && none_low ? kChunkAllOffscreen : kChunkClassify;
}

}  // namespace cuda
}  // namespace flashgs
