// Chunk culling: the bounds of every chunk of 256 consecutive Gaussians (once per scene, on
// the device, or per page as a pooled scene's pages arrive), the per-frame constants of the test in chunk_cull.cuh, and the per-frame list
// of the chunks that preprocess must read.
#include <math.h>

#include <cub/block/block_reduce.cuh>

#include <algorithm>
#include <cmath>

#include "chunk_cull.cuh"
#include "device_common.cuh"
#include "flashgs/model_constants.h"
#include "flashgs/splat_kernel.h"
#include "pipeline.h"
#include "scene_access.cuh"

namespace flashgs {
namespace cuda {
namespace {

// Beyond this a float view transform or projection could lose the chunk test's margins.
constexpr float kMaxBoundedValue = 1e18f;

__device__ bool bounded(float v) { return fabsf(v) <= kMaxBoundedValue; }  // false for NaN, Inf

struct Smaller {
  __device__ float operator()(float a, float b) const { return fminf(a, b); }
};
struct Larger {
  __device__ float operator()(float a, float b) const { return fmaxf(a, b); }
};

// A block per chunk: chunk b, or with `pages` (a pooled scene) chunk pages[b].x of pages[b].y members.
__global__ void __launch_bounds__(kChunkSize) chunk_bounds_kernel(DeviceScene scene, ChunkBound* bounds,
                                                                  const uint2* pages) {
  using Reduce = cub::BlockReduce<float, kChunkSize>;
  __shared__ typename Reduce::TempStorage storage;
  __shared__ float centre[3];
  __shared__ float shared_radius, shared_scale, shared_min_opacity;
  __shared__ int all_bounded;
  const std::size_t chunk = pages ? pages[blockIdx.x].x : blockIdx.x;
  const std::size_t first_index = chunk * kChunkSize;
  const unsigned members = pages ? pages[blockIdx.x].y
                                 : static_cast<unsigned>(scene.count - first_index < kChunkSize ? scene.count - first_index
                                                                                                 : kChunkSize);
  const std::size_t i = first_index + threadIdx.x;
  const bool valid = threadIdx.x < members;
  GaussianShape g{{0, 0, 0}, 0, {1, 0, 0, 0}, {0, 0, 0}, 0};
  if (valid) g = load_shape(scene, i);
  const float* q = g.quaternion;
  const float q_norm2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  const bool ok = !valid || (bounded(g.position[0]) && bounded(g.position[1]) && bounded(g.position[2]) &&
                             bounded(g.opacity) && bounded(g.scale[0]) && bounded(g.scale[1]) && bounded(g.scale[2]) &&
                             fabsf(q_norm2 - 1.0f) <= 1e-3f);
  if (threadIdx.x == 0) all_bounded = 1;
  __syncthreads();
  if (!ok) all_bounded = 0;

  // The box of the centres (an invalid thread repeats the chunk's first Gaussian).
  const float4 first = load_position_opacity(scene, first_index);
  const float p[3] = {valid ? g.position[0] : first.x, valid ? g.position[1] : first.y,
                      valid ? g.position[2] : first.z};
  for (int a = 0; a < 3; ++a) {
    const float lo = Reduce(storage).Reduce(p[a], Smaller());
    __syncthreads();
    const float hi = Reduce(storage).Reduce(p[a], Larger());
    __syncthreads();
    if (threadIdx.x == 0) centre[a] = 0.5f * lo + 0.5f * hi;
  }
  __syncthreads();
  double d2 = 0;
  for (int a = 0; a < 3; ++a) {
    const double d = double(p[a]) - centre[a];
    d2 += d * d;
  }
  const float radius = Reduce(storage).Reduce(static_cast<float>(sqrt(d2)), Larger());
  __syncthreads();
  const float scale = fmaxf(fabsf(g.scale[0]), fmaxf(fabsf(g.scale[1]), fabsf(g.scale[2])));
  const float max_scale = Reduce(storage).Reduce(valid ? scale : 0.0f, Larger());
  __syncthreads();
  const float min_opacity = Reduce(storage).Reduce(valid ? g.opacity : INFINITY, Smaller());
  if (threadIdx.x == 0) {
    shared_radius = radius;
    shared_scale = max_scale;
    shared_min_opacity = min_opacity;
  }
  __syncthreads();
  if (threadIdx.x == 0) {
    ChunkBound b;
    b.cx = centre[0];
    b.cy = centre[1];
    b.cz = centre[2];
    // Rounded up: the float of a distance may be below the distance.
    b.radius = shared_radius * (1.0f + 1e-6f) + 1e-30f;
    b.max_scale = shared_scale;
    b.min_opacity = shared_min_opacity;
    b.cullable = all_bounded != 0 && bounded(b.radius) ? 1u : 0u;
    b.members = members;
    bounds[chunk] = b;
  }
}

__global__ void __launch_bounds__(kChunkSize) chunk_list_kernel(DeviceScene scene, FrameBuffers buf,
                                                                gm::CameraParams cam, gm::GeometryParams geo,
                                                                ChunkCullFrame frame, unsigned chunks) {
  const unsigned t = blockIdx.x * kChunkSize + threadIdx.x;
  const bool real = t < chunks;
  const unsigned c = real && scene.draw_chunks ? scene.draw_chunks[t] : t;
  ChunkVerdict verdict = kChunkAllOffscreen;
  unsigned members = 0;
  if (real) {
    const ChunkBound b = scene.chunks[c];
    verdict = chunk_verdict(b, cam, geo, frame);
    members = b.members;
  }
  const bool listed = real && (verdict == kChunkProject || verdict == kChunkClassify);
  const unsigned ballot = __ballot_sync(kFullMask, listed);
  const unsigned lane = lane_id();
  unsigned base = 0;
  if (lane == 0 && ballot) base = atomicAdd(&buf.counters->listed_chunks, static_cast<unsigned>(__popc(ballot)));
  base = __shfl_sync(kFullMask, base, 0);
  if (listed) buf.chunk_list[base + __popc(ballot & ((1u << lane) - 1u))] = c << 1 | (verdict == kChunkClassify);
  // Wholly culled chunks are counted here without reading a Gaussian: one atomic per warp.
  const unsigned near = __reduce_add_sync(kFullMask, real && verdict == kChunkAllNear ? members : 0u);
  const unsigned offscreen = __reduce_add_sync(kFullMask, real && verdict == kChunkAllOffscreen ? members : 0u);
  if (lane == 0 && near + offscreen > 0) {
    if (near) atomicAdd(&buf.counters->by_reason[gm::kCulledNear], near);
    if (offscreen) atomicAdd(&buf.counters->by_reason[gm::kCulledOffscreen], offscreen);
    atomicAdd(&buf.counters->chunk_culled, static_cast<unsigned long long>(near + offscreen));
  }
}

}  // namespace

ChunkCullFrame chunk_cull_frame(const gm::CameraParams& cam, const gm::GeometryParams& geo, float max_opacity) {
  const double tau = geo.tau > 0.0f ? geo.tau : 1.0;
  const double s = std::sqrt(std::max(9.0, 2.0 * std::log(std::max(1.0, double(max_opacity)) / tau)));
  // The Jacobian's directions are clamped to the frustum widened by kFrustumMargin.
  const double margin_x = model::kFrustumMargin * cam.width, margin_y = model::kFrustumMargin * cam.height;
  const double tx = std::max(std::abs(cam.cx + 0.5 + margin_x), std::abs(cam.width - 0.5 - cam.cx + margin_x)) / cam.fx;
  const double ty = std::max(std::abs(cam.cy + 0.5 + margin_y), std::abs(cam.height - 0.5 - cam.cy + margin_y)) / cam.fy;
  const double k = 1.01 * std::sqrt(double(cam.fx) * cam.fx * (1.0 + tx * tx) + double(cam.fy) * cam.fy * (1.0 + ty * ty));
  // pixels: ceil (1), dilation and floor (0.79 s at 3DGS's 0.3 px^2 dilation, growing as its root), rounding (2)
  const double pad = 3.0 + 0.79 * s * std::sqrt(std::max(1.0, double(geo.dilation) / kClassicDilation));
  const double right = double(gm::kTileSize) * cam.tiles_x + pad - cam.cx;
  const double bottom = double(gm::kTileSize) * cam.tiles_y + pad - cam.cy;
  const double normals[4][3] = {{cam.fx, 0.0, -right},
                                {-double(cam.fx), 0.0, -(cam.cx + pad)},
                                {0.0, cam.fy, -bottom},
                                {0.0, -double(cam.fy), -(cam.cy + pad)}};
  ChunkCullFrame f{};
  for (int e = 0; e < 4; ++e) {
    double length2 = 0;
    for (int a = 0; a < 3; ++a) {
      f.edge_normal[e][a] = static_cast<float>(normals[e][a]);
      length2 += normals[e][a] * normals[e][a];
    }
    f.edge_normal_length[e] = static_cast<float>(std::sqrt(length2) * (1.0 + 1e-6));
  }
  f.reach_per_sigma = static_cast<float>(1.001 * s * k);
  f.jacobian_bound = static_cast<float>(k);
  return f;
}

void launch_chunk_list(const DeviceScene& scene, const FrameBuffers& b, const PreprocessArgs& args,
                       cudaStream_t stream) {
  const unsigned chunks = scene.draw_chunks ? scene.draw_chunk_count
                                            : static_cast<unsigned>((scene.count + kChunkSize - 1) / kChunkSize);
  if (chunks == 0) return;
  chunk_list_kernel<<<(chunks + kChunkSize - 1) / kChunkSize, kChunkSize, 0, stream>>>(
      scene, b, args.camera, args.geometry, args.chunk_frame, chunks);
  check_cuda(cudaGetLastError(), "chunk list kernel launch");
}

void launch_chunk_bounds(const DeviceScene& scene, ChunkBound* bounds, cudaStream_t stream) {
  if (scene.count == 0) return;
  const unsigned chunks = static_cast<unsigned>((scene.count + kChunkSize - 1) / kChunkSize);
  chunk_bounds_kernel<<<chunks, kChunkSize, 0, stream>>>(scene, bounds, nullptr);
  check_cuda(cudaGetLastError(), "chunk bounds kernel launch");
}

void launch_page_bounds(const DeviceScene& scene, const uint2* pages, unsigned count, cudaStream_t stream) {
  if (count == 0) return;
  chunk_bounds_kernel<<<count, kChunkSize, 0, stream>>>(scene, scene.chunks, pages);
  check_cuda(cudaGetLastError(), "page bounds kernel launch");
}

}  // namespace cuda
}  // namespace flashgs
