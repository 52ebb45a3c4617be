// Stage `blend`: front-to-back compositing of each tile's depth-sorted Gaussians, either the
// 3DGS way (a thread per pixel, 256-Gaussian shared-memory batches) or the FlashGS way (a warp
// per tile, each lane owning a 2x4 pixel block, batches prefetched one ahead).
#include <math.h>

#include "device_common.cuh"
#include "flashgs/gaussian_math.h"
#include "pipeline.h"

namespace flashgs {
namespace cuda {
namespace {

constexpr int kTile = gm::kTileSize;
constexpr float kLog2AlphaMin = -7.99435344f;  // log2(1/255)

// Writes one finished pixel: float RGB, or RGBA8 through the surface.
template <bool SURFACE>
__device__ __forceinline__ void write_pixel(const BlendArgs& a, int x, int y, float r, float g, float b) {
  if constexpr (SURFACE) {
    auto to_u8 = [](float v) {
      v = v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);
      return static_cast<unsigned char>(v * 255.0f + 0.5f);
    };
    surf2Dwrite(make_uchar4(to_u8(r), to_u8(g), to_u8(b), 255), static_cast<cudaSurfaceObject_t>(a.surface),
                x * 4, y);
  } else {
    float* out = a.image_rgb + (static_cast<std::size_t>(y) * a.width + x) * 3;
    out[0] = r;
    out[1] = g;
    out[2] = b;
  }
}

__device__ __forceinline__ BlendGaussian load_gaussian(const BlendGaussian* g) {
  BlendGaussian r;
  const float4* src = reinterpret_cast<const float4*>(g);
  const float4 p = __ldg(src), q = __ldg(src + 1), s = __ldg(src + 2);
  r.mean_x = p.x, r.mean_y = p.y, r.w0 = p.z, r.w1 = p.w;
  r.w2 = q.x, r.w3 = q.y, r.opacity = q.z, r.red = q.w;
  r.green = s.x, r.blue = s.y, r.reach_y = s.z, r.pad0 = 0.0f;
  return r;
}

// The 3DGS render kernel: one 16x16 block per tile, one thread per pixel. The arithmetic is
// the CPU's operation for operation (this file is built with -fmad=false), with expf.
template <bool SURFACE>
__global__ void __launch_bounds__(kTile * kTile) blend_per_pixel_kernel(BlendArgs a) {
  __shared__ BlendGaussian batch[kTile * kTile];
  const unsigned tile = blockIdx.x;
  const int tx = static_cast<int>(tile % a.tiles_x), ty = static_cast<int>(tile / a.tiles_x);
  const int x = tx * kTile + static_cast<int>(threadIdx.x % kTile);
  const int y = ty * kTile + static_cast<int>(threadIdx.x / kTile);
  const bool inside = x < a.width && y < a.height;
  bool done = !inside;
  const uint2 range = a.tile_ranges[tile];
  const float fx = static_cast<float>(x), fy = static_cast<float>(y);
  float t = 1.0f, cr = 0.0f, cg = 0.0f, cb = 0.0f;
  for (unsigned base = range.x; base < range.y; base += kTile * kTile) {
    if (__syncthreads_count(done) == kTile * kTile) break;
    const unsigned idx = base + threadIdx.x;
    if (idx < range.y) batch[threadIdx.x] = load_gaussian(a.gaussians + a.values[idx]);
    __syncthreads();
    const unsigned n = min(static_cast<unsigned>(kTile * kTile), range.y - base);
    for (unsigned j = 0; j < n && !done; ++j) {
      const BlendGaussian& g = batch[j];
      const float dx = fx - g.mean_x, dy = fy - g.mean_y;
      // Whitened form, as the CPU: q >= 0 by construction, so no "power > 0" skip.
      const float u = g.w0 * dx + g.w1 * dy, v = g.w2 * dx + g.w3 * dy;
      const float power = -0.5f * (u * u + v * v);
      const float alpha = fminf(gm::kAlphaMax, g.opacity * expf(power));
      if (alpha < gm::kAlphaMin) continue;
      const float next_t = t * (1.0f - alpha);
      if (next_t < gm::kTransmittanceMin) {
        done = true;
        break;
      }
      const float w = alpha * t;
      cr += g.red * w;
      cg += g.green * w;
      cb += g.blue * w;
      t = next_t;
    }
    __syncthreads();
  }
  if (inside) write_pixel<SURFACE>(a, x, y, cr + t * a.background[0], cg + t * a.background[1],
                                   cb + t * a.background[2]);
}

constexpr int kWarpsPerBlock = 4;
constexpr int kLanePixelsX = 2;  // 8 lanes across x 2 pixels = the tile's 16 columns

// FlashGS render kernel: a warp per strip of 4 x ROWS rows of a tile (ROWS = 4: a warp per
// tile, each lane a 2x4 pixel block, as in FlashGS; ROWS = 1: four warps per tile, each lane
// 2x1 pixels, four times the parallelism on the heavy tiles that set the kernel's length).
// Each warp walks its tile's list on its own, so it stops as soon as its own pixels are
// opaque, with no block barrier. Lanes load 32 Gaussians at once (coalesced id reads,
// independent attribute loads), stage them in shared memory and read them back as
// broadcasts. PIPELINED issues the next batch's loads before blending the current one, so
// their latency hides behind the current batch. EXP2: alpha = exp2(log2 o - q') from the
// pre-scaled whitened rows, with the 1/255 cut made on the exponent before any exp2.
template <int ROWS, bool PIPELINED, bool EXP2, bool SURFACE>
__global__ void __launch_bounds__(kWarpsPerBlock * kWarp) blend_warp_tile_kernel(BlendArgs a) {
  constexpr int kPixels = kLanePixelsX * ROWS;
  constexpr unsigned kStripsPerTile = 4 / ROWS;
  __shared__ BlendGaussian batch[kWarpsPerBlock][kWarp];
  const unsigned warp = threadIdx.x / kWarp, lane = lane_id();
  const unsigned strip = blockIdx.x * kWarpsPerBlock + warp;
  const unsigned tile = strip / kStripsPerTile;
  if (tile >= static_cast<unsigned>(a.tiles_x) * static_cast<unsigned>(a.tiles_y)) return;  // whole warp
  const int tx = static_cast<int>(tile % a.tiles_x), ty = static_cast<int>(tile / a.tiles_x);
  const int x0 = tx * kTile + static_cast<int>(lane % 8) * kLanePixelsX;
  const int y0 = ty * kTile + static_cast<int>(strip % kStripsPerTile) * 4 * ROWS + static_cast<int>(lane / 8) * ROWS;
  const float strip_half_h = 0.5f * (4 * ROWS - 1);
  const float strip_mid_y =
      static_cast<float>(ty * kTile + static_cast<int>(strip % kStripsPerTile) * 4 * ROWS) + strip_half_h;
  float t[kPixels], cr[kPixels], cg[kPixels], cb[kPixels];
  unsigned live = 0;  // bit p: pixel p still blending
#pragma unroll
  for (int p = 0; p < kPixels; ++p) {
    t[p] = 1.0f;
    cr[p] = cg[p] = cb[p] = 0.0f;
    const int x = x0 + p % kLanePixelsX, y = y0 + p / kLanePixelsX;
    if (x < a.width && y < a.height) live |= 1u << p;
  }
  const unsigned inside = live;
  const uint2 range = a.tile_ranges[tile];
  BlendGaussian next{};
  if (PIPELINED && range.x + lane < range.y) next = load_gaussian(a.gaussians + a.values[range.x + lane]);
  for (unsigned base = range.x; base < range.y; base += kWarp) {
    if (!__any_sync(kFullMask, live)) break;
    if (!PIPELINED && base + lane < range.y) next = load_gaussian(a.gaussians + a.values[base + lane]);
    __syncwarp();
    batch[warp][lane] = next;
    __syncwarp();
    if (PIPELINED && base + kWarp + lane < range.y)
      next = load_gaussian(a.gaussians + a.values[base + kWarp + lane]);
    const unsigned n = min(static_cast<unsigned>(kWarp), range.y - base);
    for (unsigned j = 0; j < n && live; ++j) {
      const BlendGaussian& g = batch[warp][j];
      // The whole strip lies beyond the rows this Gaussian can reach: a warp-uniform skip.
      if (fabsf(strip_mid_y - g.mean_y) > g.reach_y + strip_half_h) continue;
      // Per lane, the columns' and rows' parts of u and v, so a pixel costs two adds and a
      // square-sum; in the exact mode this is the CPU's rounding, term for term.
      float ux[kLanePixelsX], vx[kLanePixelsX], uy[ROWS], vy[ROWS];
#pragma unroll
      for (int c = 0; c < kLanePixelsX; ++c) {
        const float dx = static_cast<float>(x0 + c) - g.mean_x;
        ux[c] = g.w0 * dx;
        vx[c] = g.w2 * dx;
      }
#pragma unroll
      for (int r = 0; r < ROWS; ++r) {
        const float dy = static_cast<float>(y0 + r) - g.mean_y;
        uy[r] = g.w1 * dy;
        vy[r] = g.w3 * dy;
      }
#pragma unroll
      for (int p = 0; p < kPixels; ++p) {
        if (!(live & (1u << p))) continue;
        const int c = p % kLanePixelsX, r = p / kLanePixelsX;
        const float u = ux[c] + uy[r], v = vx[c] + vy[r];
        float alpha;
        if constexpr (EXP2) {
          const float e = g.opacity - __fmaf_rn(u, u, v * v);  // log2 o - q'
          if (e < kLog2AlphaMin) continue;
          alpha = fminf(gm::kAlphaMax, exp2f(e));
        } else {
          const float power = -0.5f * (u * u + v * v);
          alpha = fminf(gm::kAlphaMax, g.opacity * expf(power));
          if (alpha < gm::kAlphaMin) continue;
        }
        const float next_t = t[p] * (1.0f - alpha);
        if (next_t < gm::kTransmittanceMin) {
          live &= ~(1u << p);
          continue;
        }
        const float w = alpha * t[p];
        cr[p] += g.red * w;
        cg[p] += g.green * w;
        cb[p] += g.blue * w;
        t[p] = next_t;
      }
    }
  }
#pragma unroll
  for (int p = 0; p < kPixels; ++p)
    if (inside & (1u << p))
      write_pixel<SURFACE>(a, x0 + p % kLanePixelsX, y0 + p / kLanePixelsX, cr[p] + t[p] * a.background[0],
                           cg[p] + t[p] * a.background[1], cb[p] + t[p] * a.background[2]);
}

template <int ROWS, bool SURFACE>
void launch_warp_tile(const BlendArgs& a, unsigned tiles, cudaStream_t stream) {
  const unsigned strips = tiles * (4 / ROWS);
  const unsigned blocks = (strips + kWarpsPerBlock - 1) / kWarpsPerBlock;
  const unsigned threads = kWarpsPerBlock * kWarp;
  const bool pipelined = a.kernel == BlendKernel::warp_tile_pipelined;
  if (pipelined && a.exp2_alpha) blend_warp_tile_kernel<ROWS, true, true, SURFACE><<<blocks, threads, 0, stream>>>(a);
  else if (pipelined) blend_warp_tile_kernel<ROWS, true, false, SURFACE><<<blocks, threads, 0, stream>>>(a);
  else if (a.exp2_alpha) blend_warp_tile_kernel<ROWS, false, true, SURFACE><<<blocks, threads, 0, stream>>>(a);
  else blend_warp_tile_kernel<ROWS, false, false, SURFACE><<<blocks, threads, 0, stream>>>(a);
}

template <bool SURFACE>
void launch_for_output(const BlendArgs& a, cudaStream_t stream) {
  const unsigned tiles = static_cast<unsigned>(a.tiles_x) * static_cast<unsigned>(a.tiles_y);
  if (a.kernel == BlendKernel::per_pixel) {
    blend_per_pixel_kernel<SURFACE><<<tiles, kTile * kTile, 0, stream>>>(a);
    return;
  }
  switch (a.lane_rows) {
    case 4: launch_warp_tile<4, SURFACE>(a, tiles, stream); break;
    case 2: launch_warp_tile<2, SURFACE>(a, tiles, stream); break;
    default: launch_warp_tile<1, SURFACE>(a, tiles, stream); break;
  }
}

}  // namespace

void launch_blend(const BlendArgs& args, cudaStream_t stream) {
  if (args.image_rgb) launch_for_output<false>(args, stream);
  else launch_for_output<true>(args, stream);
  check_cuda(cudaGetLastError(), "blend kernel launch");
}

}  // namespace cuda
}  // namespace flashgs
