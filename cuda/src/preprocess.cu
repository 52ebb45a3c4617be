// Stage `project` (+ fused `emit`): cull, 2D footprint, SH colour and, in the FlashGS path,
// the Gaussian-tile keys, all in one pass over the scene.
#include <math.h>

#include "device_common.cuh"
#include "flashgs/gaussian_math.h"
#include "pipeline.h"

namespace flashgs {
namespace cuda {
namespace {

constexpr int kBlock = 256;
constexpr float kLog2e = 1.4426950408889634f;

// Higher SH bands of Gaussian i into registers: only the float4s that DEGREE needs are read,
// whatever degree the scene was stored with.
template <int DEGREE>
__device__ __forceinline__ void colour(const DeviceScene& scene, unsigned i, const gm::CameraParams& cam,
                                       const float pos[3], const float dc[3], float rgb[3]) {
  if constexpr (DEGREE == 0) {
    gm::sh_to_rgb<0>(cam.position, pos, dc, nullptr, rgb);
  } else {
    constexpr int kRest = ((DEGREE + 1) * (DEGREE + 1) - 1) * 3;
    constexpr int kVec = (kRest + 3) / 4;
    float rest[kVec * 4];
    const float4* src = scene.sh_rest + static_cast<std::size_t>(i) * scene.rest_stride_vec4;
#pragma unroll
    for (int k = 0; k < kVec; ++k) {
      const float4 v = __ldg(src + k);
      rest[4 * k + 0] = v.x;
      rest[4 * k + 1] = v.y;
      rest[4 * k + 2] = v.z;
      rest[4 * k + 3] = v.w;
    }
    gm::sh_to_rgb<DEGREE>(cam.position, pos, dc, rest, rgb);
  }
}

// The whole footprint of lane `src`, word by word, so that no field can be forgotten.
__device__ __forceinline__ gm::Footprint shfl_footprint(const gm::Footprint& f, int src) {
  static_assert(sizeof(gm::Footprint) % 4 == 0, "footprint is made of 32-bit words");
  constexpr int kWords = sizeof(gm::Footprint) / 4;
  unsigned words[kWords];
  memcpy(words, &f, sizeof(f));
#pragma unroll
  for (int k = 0; k < kWords; ++k) words[k] = __shfl_sync(kFullMask, words[k], src);
  gm::Footprint g;
  memcpy(&g, words, sizeof(g));
  return g;
}

__device__ __forceinline__ bool touches(const gm::Footprint& f, int tx, int ty, const gm::CameraParams& cam,
                                        bool exact) {
  return !exact || gm::footprint_touches_tile(f, tx, ty, cam.width, cam.height);
}

// One thread per Gaussian. FUSED: keys are written here (FlashGS); otherwise the footprint
// and the pair count are stored for the separate prefix sum + duplicate pass (3DGS).
template <int DEGREE, bool FUSED>
__global__ void __launch_bounds__(kBlock) preprocess_kernel(DeviceScene scene, FrameBuffers buf,
                                                            PreprocessArgs args) {
  __shared__ unsigned block_counts[5];  // visible, near, offscreen, low opacity, degenerate
  if (threadIdx.x < 5) block_counts[threadIdx.x] = 0;
  __syncthreads();

  const unsigned i = blockIdx.x * kBlock + threadIdx.x;
  const unsigned lane = lane_id();
  const bool valid = i < scene.count;
  const gm::CameraParams& cam = args.camera;

  gm::Footprint f{};
  int reason = gm::kCulledDegenerate;
  unsigned count = 0;          // pairs of this Gaussian (small path / separate path)
  unsigned passed_mask = 0;    // tiles of a box of <= 32 tiles that passed the exact test
  bool large = false;          // emitted by the whole warp below
  bool huge = false;           // emitted by huge_emit_kernel (counted there too)
  if (valid) {
    const float4 po = __ldg(scene.position_opacity + i);
    const float4 q = __ldg(scene.rotation + i);
    const float4 sd = __ldg(scene.scale_dc_r + i);
    const float pos[3] = {po.x, po.y, po.z};
    const float scale[3] = {sd.x, sd.y, sd.z};
    const float quat[4] = {q.x, q.y, q.z, q.w};
    reason = gm::project(cam, args.geometry, pos, scale, quat, po.w, f);
    if (reason == gm::kVisible) {
      const float2 gb = __ldg(scene.dc_gb + i);
      const float dc[3] = {sd.w, gb.x, gb.y};
      float rgb[3];
      colour<DEGREE>(scene, i, cam, pos, dc, rgb);
      float4* out = reinterpret_cast<float4*>(buf.blend + i);
      if (args.exp2_alpha) {
        // w' = sqrt(log2(e) / 2) w, so o e^(-q/2) = exp2(log2 o - (u'^2 + v'^2)): one exp2.
        const float hs = sqrtf(0.5f * kLog2e);
        out[0] = make_float4(f.mean_x, f.mean_y, hs * f.whiten[0], hs * f.whiten[1]);
        out[1] = make_float4(hs * f.whiten[2], hs * f.whiten[3], log2f(po.w), rgb[0]);
      } else {
        out[0] = make_float4(f.mean_x, f.mean_y, f.whiten[0], f.whiten[1]);
        out[1] = make_float4(f.whiten[2], f.whiten[3], po.w, rgb[0]);
      }
      // Rows farther than reach_y from the centre have q > 2 ln(255 o), i.e. alpha < 1/255
      // (min over dx of q at offset dy is dy^2 / Sigma_yy); the margins cover rounding, so
      // the blend may skip them without changing a pixel.
      const float det_w = f.whiten[0] * f.whiten[3] - f.whiten[1] * f.whiten[2];
      const float q_cut = 2.0f * logf(255.0f * po.w) + 0.01f;
      const float conic_a = f.whiten[0] * f.whiten[0] + f.whiten[2] * f.whiten[2];
      float reach_y = q_cut > 0.0f ? sqrtf(q_cut * conic_a) / fabsf(det_w) + 0.01f : -1.0f;
      if (!(reach_y < 1e30f) && q_cut > 0.0f) reach_y = 1e30f;  // degenerate: never skip
      out[2] = make_float4(rgb[1], rgb[2], reach_y, 0.0f);

      const int box_w = f.tile_x1 - f.tile_x0;
      const unsigned box = static_cast<unsigned>(box_w) * static_cast<unsigned>(f.tile_y1 - f.tile_y0);
      if (FUSED && args.warp_cooperative && box > static_cast<unsigned>(kHugeBoxTiles)) {
        const unsigned slot = atomicAdd(&buf.counters->huge, 1u);
        if (slot < buf.huge_capacity) {
          buf.huge_footprints[slot] = f;
          buf.huge_ids[slot] = i;
          huge = true;
        } else {
          large = true;
        }
      } else if (FUSED && args.warp_cooperative && box > static_cast<unsigned>(kLargeBoxTiles)) {
        large = true;
      } else if (!args.exact_tile_test) {
        count = box;
      } else {
        unsigned k = 0;
        for (int ty = f.tile_y0; ty < f.tile_y1; ++ty)
          for (int tx = f.tile_x0; tx < f.tile_x1; ++tx, ++k)
            if (gm::footprint_touches_tile(f, tx, ty, cam.width, cam.height)) {
              ++count;
              if (k < 32) passed_mask |= 1u << k;
            }
      }
    }
  }

  if constexpr (FUSED) {
    const std::uint32_t depth_bits = gm::depth_bits(f.depth);
    // Thread-emitted Gaussians: one atomic per warp reserves all their pairs.
    const unsigned inclusive = warp_inclusive_sum(count);
    const unsigned warp_total = __shfl_sync(kFullMask, inclusive, kWarp - 1);
    unsigned long long base = 0;
    if (lane == kWarp - 1 && warp_total > 0) base = atomicAdd(&buf.counters->pairs, warp_total);
    base = __shfl_sync(kFullMask, base, kWarp - 1);
    if (count > 0) {
      unsigned long long offset = base + inclusive - count;
      const int box_w = f.tile_x1 - f.tile_x0;
      const unsigned box = static_cast<unsigned>(box_w) * static_cast<unsigned>(f.tile_y1 - f.tile_y0);
      if (args.exact_tile_test && box <= 32) {
        for (unsigned m = passed_mask; m; m &= m - 1) {
          const unsigned k = __ffs(m) - 1;
          const unsigned tile = (f.tile_y0 + k / box_w) * cam.tiles_x + f.tile_x0 + k % box_w;
          store_pair(buf, offset++, tile, depth_bits, i);
        }
      } else {
        for (int ty = f.tile_y0; ty < f.tile_y1; ++ty)
          for (int tx = f.tile_x0; tx < f.tile_x1; ++tx)
            if (touches(f, tx, ty, cam, args.exact_tile_test))
              store_pair(buf, offset++, static_cast<unsigned>(ty) * cam.tiles_x + tx, depth_bits, i);
      }
    }
    // Large Gaussians: the warp tests 32 tiles at a time and writes the hits with ballot +
    // popc offsets after one atomic per chunk (FlashGS section 4.3).
    unsigned pending = __ballot_sync(kFullMask, large);
    while (pending) {
      const int src = __ffs(pending) - 1;
      pending &= pending - 1;
      const gm::Footprint g = shfl_footprint(f, src);
      const std::uint32_t g_depth = __shfl_sync(kFullMask, depth_bits, src);
      const unsigned g_id = __shfl_sync(kFullMask, i, src);
      const unsigned box_w = static_cast<unsigned>(g.tile_x1 - g.tile_x0);
      const unsigned box = box_w * static_cast<unsigned>(g.tile_y1 - g.tile_y0);
      // One pass: each 32-tile chunk is tested, then reserved with one atomic for its hits.
      const unsigned lanes_below = (1u << lane) - 1u;
      unsigned total = 0;
      for (unsigned t0 = 0; t0 < box; t0 += kWarp) {
        const unsigned t = t0 + lane;
        const unsigned tx = g.tile_x0 + t % box_w, ty = g.tile_y0 + t / box_w;
        const bool pass = t < box && touches(g, tx, ty, cam, args.exact_tile_test);
        const unsigned ballot = __ballot_sync(kFullMask, pass);
        if (!ballot) continue;
        unsigned long long chunk_base = 0;
        if (lane == 0) chunk_base = atomicAdd(&buf.counters->pairs, static_cast<unsigned long long>(__popc(ballot)));
        chunk_base = __shfl_sync(kFullMask, chunk_base, 0);
        if (pass) store_pair(buf, chunk_base + __popc(ballot & lanes_below), ty * cam.tiles_x + tx, g_depth, g_id);
        total += __popc(ballot);
      }
      if (static_cast<int>(lane) == src) count = total;
    }
  } else {
    if (valid) {
      buf.pair_counts[i] = count;
      if (count > 0) buf.footprints[i] = f;
    }
    const unsigned warp_total = __reduce_add_sync(kFullMask, count);
    if (lane == 0 && warp_total > 0) atomicAdd(&buf.counters->pairs, static_cast<unsigned long long>(warp_total));
  }

  if (valid && !huge) {
    int slot;
    if (reason == gm::kVisible) slot = count > 0 ? 0 : 2;  // box met the image, the ellipse did not
    else if (reason == gm::kCulledNear) slot = 1;
    else if (reason == gm::kCulledOffscreen) slot = 2;
    else if (reason == gm::kCulledLowOpacity) slot = 3;
    else slot = 4;
    atomicAdd(&block_counts[slot], 1u);
  }
  __syncthreads();
  if (threadIdx.x < 5 && block_counts[threadIdx.x] > 0) {
    unsigned* dst = threadIdx.x == 0 ? &buf.counters->visible : &buf.counters->culled_near + (threadIdx.x - 1);
    atomicAdd(dst, block_counts[threadIdx.x]);
  }
}

// The deferred huge Gaussians: a block per Gaussian, each warp a 32-tile chunk at a time,
// one atomic per chunk with hits; visibility is decided here from the block's total.
__global__ void __launch_bounds__(kBlock) huge_emit_kernel(FrameBuffers buf, gm::CameraParams cam, bool exact) {
  __shared__ unsigned block_total;
  const unsigned count = min(buf.counters->huge, buf.huge_capacity);
  const unsigned lane = lane_id(), warp = threadIdx.x / kWarp;
  const unsigned lanes_below = (1u << lane) - 1u;
  for (unsigned h = blockIdx.x; h < count; h += gridDim.x) {
    if (threadIdx.x == 0) block_total = 0;
    __syncthreads();
    const gm::Footprint f = buf.huge_footprints[h];
    const unsigned id = buf.huge_ids[h];
    const std::uint32_t depth_bits = gm::depth_bits(f.depth);
    const unsigned box_w = static_cast<unsigned>(f.tile_x1 - f.tile_x0);
    const unsigned box = box_w * static_cast<unsigned>(f.tile_y1 - f.tile_y0);
    unsigned warp_total = 0;
    for (unsigned t0 = warp * kWarp; t0 < box; t0 += kBlock) {
      const unsigned t = t0 + lane;
      const unsigned tx = f.tile_x0 + t % box_w, ty = f.tile_y0 + t / box_w;
      const bool pass = t < box && touches(f, tx, ty, cam, exact);
      const unsigned ballot = __ballot_sync(kFullMask, pass);
      if (!ballot) continue;
      unsigned long long base = 0;
      if (lane == 0) base = atomicAdd(&buf.counters->pairs, static_cast<unsigned long long>(__popc(ballot)));
      base = __shfl_sync(kFullMask, base, 0);
      if (pass) store_pair(buf, base + __popc(ballot & lanes_below), ty * cam.tiles_x + tx, depth_bits, id);
      warp_total += __popc(ballot);
    }
    if (lane == 0 && warp_total) atomicAdd(&block_total, warp_total);
    __syncthreads();
    if (threadIdx.x == 0) atomicAdd(block_total > 0 ? &buf.counters->visible : &buf.counters->culled_offscreen, 1u);
  }
}

template <bool FUSED>
void launch_for_degree(const DeviceScene& scene, const FrameBuffers& buffers, const PreprocessArgs& args,
                       cudaStream_t stream) {
  const unsigned blocks = static_cast<unsigned>((scene.count + kBlock - 1) / kBlock);
  switch (args.sh_degree) {
    case 0: preprocess_kernel<0, FUSED><<<blocks, kBlock, 0, stream>>>(scene, buffers, args); break;
    case 1: preprocess_kernel<1, FUSED><<<blocks, kBlock, 0, stream>>>(scene, buffers, args); break;
    case 2: preprocess_kernel<2, FUSED><<<blocks, kBlock, 0, stream>>>(scene, buffers, args); break;
    default: preprocess_kernel<3, FUSED><<<blocks, kBlock, 0, stream>>>(scene, buffers, args); break;
  }
}

}  // namespace

void launch_preprocess(const DeviceScene& scene, const FrameBuffers& buffers, const PreprocessArgs& args,
                       bool fused, cudaStream_t stream) {
  if (scene.count == 0) return;
  if (fused) {
    launch_for_degree<true>(scene, buffers, args, stream);
    if (args.warp_cooperative && buffers.huge_capacity > 0)
      huge_emit_kernel<<<264, kBlock, 0, stream>>>(buffers, args.camera, args.exact_tile_test);
  } else {
    launch_for_degree<false>(scene, buffers, args, stream);
  }
  check_cuda(cudaGetLastError(), "preprocess kernel launch");
}

}  // namespace cuda
}  // namespace flashgs
