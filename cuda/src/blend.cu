// Stage `blend`: front-to-back compositing of each tile's depth-sorted Gaussians, either the
// 3DGS way (a thread per pixel, 256-Gaussian shared-memory batches) or the FlashGS way (warps
// walking a tile's list with 32-Gaussian batches prefetched one ahead).
#include <cuda_fp16.h>
#include <math.h>

#include <algorithm>
#include <type_traits>

#include "device_common.cuh"
#include "flashgs/gaussian_math.h"
#include "pipeline.h"

namespace flashgs {
namespace cuda {
namespace {

constexpr int kTile = gm::kTileSize;
constexpr float kLog2AlphaMin = -7.99435344f;  // log2(1/255)
constexpr float kLog2AlphaMax = -0.0144995697f;  // log2(0.99)

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
  r.green = s.x, r.blue = s.y, r.reach_y = s.z, r.depth = s.w;
  return r;
}

// The 3DGS render kernel: one 16x16 block per tile, one thread per pixel. The arithmetic is
// the CPU's operation for operation (this file is built with -fmad=false), with expf. With
// a.pixel_depth each pixel also sums its weights and weighted depths and counts its Gaussians,
// as the CPU's scalar kernel does.
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
  float weight_sum = 0.0f, weighted_depth = 0.0f;
  std::uint32_t blended = 0;
  const bool planes = a.pixel_depth != nullptr;
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
      if (planes) {
        weight_sum += w;
        weighted_depth += w * g.depth;
        ++blended;
      }
    }
    __syncthreads();
  }
  if (!inside) return;
  write_pixel<SURFACE>(a, x, y, cr + t * a.background[0], cg + t * a.background[1], cb + t * a.background[2]);
  if (planes) {
    const std::size_t at = static_cast<std::size_t>(y) * a.width + x;
    a.pixel_depth[at] = blended > 0 ? weighted_depth / weight_sum : __int_as_float(0x7fc00000);  // NaN: none
    a.pixel_blended[at] = blended;
  }
}

constexpr int kWarpsPerBlock = 4;
constexpr int kLanePixelsX = 2;      // pixels per lane, side by side in a row
constexpr int kRegionsPerTile = 4;   // 64-pixel regions, a warp each
constexpr int kBlendUnroll = 4;      // staged Gaussians per step of the loop
constexpr float kBoundWorthT = 8.0f * gm::kTransmittanceMin;  // see the staging's stop bound
// Resident blocks per SM the blend kernel is compiled for: 56 registers without spills. Left to
// itself the compiler takes 64 for the colour steps, which leaves 8 blocks and measured slower.
constexpr int kBlendBlocksPerSm = 9;

// 1/x by the hardware unit alone, for a positive normal x (no range checks, as __fdividef has).
__device__ __forceinline__ float reciprocal_approx(float x) {
  float y;
  asm("rcp.approx.ftz.f32 %0, %1;" : "=f"(y) : "f"(x));
  return y;
}

// 2^x by the hardware unit alone: x >= log2(1/255) here, so no denormal handling is needed
// (exp2f adds a range check and two scalings around the same instruction).
__device__ __forceinline__ float exp2_approx(float x) {
  float y;
  asm("ex2.approx.ftz.f32 %0, %1;" : "=f"(y) : "f"(x));
  return y;
}

// A Gaussian as the EXP2 loop reads it from shared memory: its log2 alpha as a polynomial
// in the pixel's offset (lx, ly) from the region's centre, c0 + c1 lx + c2 lx^2 with
// c0 = a0 + a1 ly + a2 ly^2 and c1 = b0 + b1 ly, the row's (c0, c1) prepared for each of the
// region's ROWS rows by the lane that loaded it (24 FMAs at 8 rows, once per region), so that a
// lane reads its row's pair and evaluates each of its pixels with two FMAs (the same roundings
// as evaluating the row in the loop, so the same image).
// Expanded about the centre, no term exceeds the exponent's range over the 8-pixel region
// (the 0.3 px^2 dilation bounds the conic), so fp32 keeps it to ~1e-5 in log2 alpha.
// Its colour is stored as the change from the Gaussian staged before it (ColourSteps).
template <int ROWS>
struct alignas(16) RegionGaussian {
  float c2, red_step, green_step, blue_step;
  float2 row[ROWS];  // (c0, c1) at row r, ly = r - (ROWS - 1) / 2
};

// The column a finished pixel moves to: NaN, so every later Gaussian's exponent there is NaN,
// fails the 1/255 cut and gives alpha 0, and the pixel keeps its transmittance, the
// background's weight, without a liveness test in the loop.
__device__ __forceinline__ float finished_column() { return __int_as_float(0x7fffffff); }

// Summation by parts for the EXP2 loop. A pixel's colour is sum_i c_i (T_i - T_i+1) over the
// Gaussians its warp visits, T_i its transmittance before the i-th; that equals
// sum_i T_i (c_i - c_i-1) - c_last T_end (c_-1 = 0). So each visit adds (c_i - c_i-1) T_i, which
// needs neither alpha nor the new T: three FMAs off the exp2's chain and no weight to form, and a
// visit that changes no T adds terms that cancel. The region's staged Gaussians are one sequence
// across its batches; `last` is the colour of the latest one staged, to be taken off at the end.
// Against sum_i c_i w_i this moves each pixel by a few float roundings of its colour per visit
// (~1e-7 each), well inside the parity bound with the CPU; T and so every stop are unchanged.
struct ColourSteps {
  float last_red = 0.0f, last_green = 0.0f, last_blue = 0.0f;

  // For the lane whose record is staged (`relevant` the warp's staged lanes): its colour minus
  // that of the staged Gaussian before it. Then `last` moves to the batch's last staged colour.
  // Every lane of the warp calls this (shuffles).
  __device__ float3 step(unsigned relevant, unsigned lane, float red, float green, float blue) {
    const unsigned before = relevant & ((1u << lane) - 1u);
    const int from = before ? 31 - __clz(before) : 0;
    float3 previous = make_float3(__shfl_sync(kFullMask, red, from), __shfl_sync(kFullMask, green, from),
                                  __shfl_sync(kFullMask, blue, from));
    if (!before) previous = make_float3(last_red, last_green, last_blue);
    if (relevant) {
      const int final_lane = 31 - __clz(relevant);
      last_red = __shfl_sync(kFullMask, red, final_lane);
      last_green = __shfl_sync(kFullMask, green, final_lane);
      last_blue = __shfl_sync(kFullMask, blue, final_lane);
    }
    return make_float3(red - previous.x, green - previous.y, blue - previous.z);
  }
};

// t = (e >= the 1/255 cut) ? t - alpha t : t as one predicated FMA (a select would be one
// instruction more per pixel). A NaN exponent (a finished or outside column) fails the cut.
__device__ __forceinline__ float transmittance_after(float t, float alpha, float e) {
  asm("{\n\t.reg .pred visible;\n\tsetp.ge.f32 visible, %1, %2;\n\t@visible fma.rn.f32 %0, %3, %0, %0;\n\t}"
      : "+f"(t)
      : "f"(e), "f"(kLog2AlphaMin), "f"(-alpha));
  return t;
}

// The same with the CPU's stop rule: a visible Gaussian that would take T below the minimum
// adds nothing, T stays (the background's weight), and the pixel's column becomes NaN, so that
// no later Gaussian passes its cut. One compare gives both outcomes ("keep" and "stop"), and
// each moves one register: selects would cost one instruction more per pixel.
__device__ __forceinline__ void transmittance_or_stop(float& t, float& column, float alpha, float e) {
  asm("{\n\t.reg .pred visible, keep, stop;\n\t.reg .f32 next;\n\t"
      "setp.ge.f32 visible, %2, %3;\n\t"
      "fma.rn.f32 next, %4, %0, %0;\n\t"
      "setp.ge.and.f32 keep|stop, next, %5, visible;\n\t"
      "@keep mov.f32 %0, next;\n\t"
      "@stop mov.f32 %1, %6;\n\t}"
      : "+f"(t), "+f"(column)
      : "f"(e), "f"(kLog2AlphaMin), "f"(-alpha), "f"(gm::kTransmittanceMin), "f"(finished_column()));
}

// A tile's blend records in list order, up to 32 at a time (lane j gets the j-th).
struct TileList {
  const std::uint32_t* values;
  unsigned cursor, end;
  __device__ unsigned take(unsigned lane, unsigned& record) {
    const unsigned n = min(static_cast<unsigned>(kWarp), end - cursor);
    if (lane < n) record = values[cursor + lane];
    cursor += n;
    return n;
  }
};

// A Gaussian as the HALF loop (RenderOptions::fp16_blend) reads it: the whitened rows at the
// region's centre and their change per pixel, so that u = u0 + w0 lx + w1 ly and likewise v,
// and log2 alpha = log2 opacity - u^2 - v^2, all in half2 arithmetic on a lane's two pixels.
// Whitened coordinates stay small where alpha passes the cut (u^2 + v^2 <= 8), which suits
// halves better than the polynomial's coefficients (RegionGaussian), whose terms cancel.
// 20 bytes of halves in a 32-byte slot, read back as one 16-byte and one 4-byte broadcast.
struct alignas(16) HalfRegionGaussian {
  __half2 uv0;         // (u, v) at the region's centre
  __half2 w_y;         // (w1, w3): their change per pixel down
  __half2 w_x;         // (w0, w2): per pixel across
  __half2 lop_red;     // log2 opacity, red
  __half2 green_blue;
  unsigned pad[3];
};

__device__ __forceinline__ unsigned half2_bits(__half2 h) {
  unsigned bits;
  memcpy(&bits, &h, sizeof bits);
  return bits;
}

__device__ __forceinline__ __half2 bits_half2(unsigned bits) {
  __half2 h;
  memcpy(&h, &bits, sizeof h);
  return h;
}

// 2^x on both halves by the hardware unit (relative error 2^-9.9).
__device__ __forceinline__ __half2 exp2_approx(__half2 x) {
  unsigned y;
  asm("ex2.approx.f16x2 %0, %1;" : "=r"(y) : "r"(half2_bits(x)));
  return bits_half2(y);
}

// One staged Gaussian on a lane's two pixels in half2 arithmetic: alpha = exp2 of log2 alpha,
// the 1/255 cut on the exponent (a column outside the image is NaN and fails it), the 0.99
// clamp, and compositing with T and the colours as halves. No stop rule per Gaussian (its test
// and selects would cost a third more): a pixel whose T fell below the minimum goes on until
// every pixel of its warp has, adding less than that T (1e-4) in all. On Hopper the f16x2 exp2
// is two MUFU.EX2.F16 and a PRMT: about 19 instructions per Gaussian and lane against the
// float loop's 29-35 (from the SASS), with the exp2 unit then nearly as busy as the issue.
__device__ __forceinline__ void blend_region_gaussian_half(const HalfRegionGaussian& g, __half2 lane_y,
                                                           __half2 lane_x, __half2 cut, __half2 alpha_max,
                                                           __half2& t, __half2& cr, __half2& cg, __half2& cb) {
  const __half2 uv_row = __hfma2(g.w_y, lane_y, g.uv0);
  const __half2 u = __hfma2(__low2half2(g.w_x), lane_x, __low2half2(uv_row));
  const __half2 v = __hfma2(__high2half2(g.w_x), lane_x, __high2half2(uv_row));
  const __half2 e = __hfma2(__hneg2(v), v, __hfma2(__hneg2(u), u, __low2half2(g.lop_red)));
  const __half2 alpha = bits_half2(half2_bits(__hmin2(exp2_approx(e), alpha_max)) & __hge2_mask(e, cut));
  const __half2 w = __hmul2(alpha, t);
  t = __hsub2(t, w);
  cr = __hfma2(__high2half2(g.lop_red), w, cr);
  cg = __hfma2(__low2half2(g.green_blue), w, cg);
  cb = __hfma2(__high2half2(g.green_blue), w, cb);
}

// One staged Gaussian on a lane's pixels (EXP2): alpha = exp2 of the polynomial, the 1/255 cut
// on the exponent, and compositing by colour steps (ColourSteps). STOP_RULE applies the CPU's
// stop; without it (a Gaussian that cannot take any of the warp's pixels below the minimum T,
// see the staging) the result is the same with three operations fewer per pixel. Likewise
// CLAMP, the 0.99 clamp, which only a Gaussian whose alpha can reach 0.99 in the region needs.
template <bool STOP_RULE, bool CLAMP, int ROWS>
__device__ __forceinline__ void blend_region_gaussian(const RegionGaussian<ROWS>& g, unsigned lane_row,
                                                      float (&lane_x)[kLanePixelsX], float (&t)[kLanePixelsX],
                                                      float (&cr)[kLanePixelsX], float (&cg)[kLanePixelsX],
                                                      float (&cb)[kLanePixelsX]) {
  const float2 row = g.row[lane_row];
  const float c0 = row.x, c1 = row.y, c2 = g.c2;
#pragma unroll
  for (int p = 0; p < kLanePixelsX; ++p) {
    const float e = __fmaf_rn(__fmaf_rn(c2, lane_x[p], c1), lane_x[p], c0);  // log2 alpha
    cr[p] = __fmaf_rn(g.red_step, t[p], cr[p]);
    cg[p] = __fmaf_rn(g.green_step, t[p], cg[p]);
    cb[p] = __fmaf_rn(g.blue_step, t[p], cb[p]);
    // The clamp after exp2 keeps alpha = 0.99f exactly for opaque Gaussians, and the FMA gives
    // T (1 - alpha) with one rounding: with 1 - alpha exact (alpha >= 1/2), the CPU's T, so the
    // stop rule's decisions on stacked opaque layers are its own.
    const float alpha = CLAMP ? fminf(gm::kAlphaMax, exp2_approx(e)) : exp2_approx(e);
    if constexpr (STOP_RULE) transmittance_or_stop(t[p], lane_x[p], alpha, e);
    else t[p] = transmittance_after(t[p], alpha, e);
  }
}

// A warp's staged Gaussians [0, staged) on its pixels, the first `unstoppable` without the stop
// rule. Unrolled: more independent work between the shared loads and the transmittance chain.
template <bool CLAMP, int ROWS>
__device__ __forceinline__ void blend_staged(const RegionGaussian<ROWS>* batch, unsigned unstoppable, unsigned staged,
                                             unsigned lane_row, float (&lane_x)[kLanePixelsX],
                                             float (&t)[kLanePixelsX], float (&cr)[kLanePixelsX],
                                             float (&cg)[kLanePixelsX], float (&cb)[kLanePixelsX]) {
#pragma unroll kBlendUnroll
  for (unsigned j = 0; j < unstoppable; ++j)
    blend_region_gaussian<false, CLAMP>(batch[j], lane_row, lane_x, t, cr, cg, cb);
#pragma unroll kBlendUnroll
  for (unsigned j = unstoppable; j < staged; ++j)
    blend_region_gaussian<true, CLAMP>(batch[j], lane_row, lane_x, t, cr, cg, cb);
}

// The staged form of a Gaussian met by a region of ROWS rows: (u0, v0) are its whitened rows at
// the region's centre and (conic_a, conic_b, conic_c) its conic, all in the exp2 scaling.
template <int ROWS>
__device__ __forceinline__ RegionGaussian<ROWS> region_gaussian(const BlendGaussian& g, float3 colour_step, float u0,
                                                                float v0, float conic_a, float conic_b,
                                                                float conic_c) {
  const float a0 = __fmaf_rn(-u0, u0, __fmaf_rn(-v0, v0, g.opacity));
  const float a1 = -2.0f * __fmaf_rn(g.w1, u0, g.w3 * v0), a2 = -conic_c;
  const float b0 = -2.0f * __fmaf_rn(g.w0, u0, g.w2 * v0), b1 = -2.0f * conic_b;
  RegionGaussian<ROWS> r;
  r.c2 = -conic_a;
  r.red_step = colour_step.x;
  r.green_step = colour_step.y;
  r.blue_step = colour_step.z;
#pragma unroll
  for (int row = 0; row < ROWS; ++row) {
    const float ly = static_cast<float>(row) - 0.5f * (ROWS - 1);  // exactly the lane's y - the centre's
    r.row[row] = make_float2(__fmaf_rn(__fmaf_rn(a2, ly, a1), ly, a0), __fmaf_rn(b1, ly, b0));
  }
  return r;
}

// FlashGS render kernel, a warp per 64-pixel region of a tile: REGION_W x (64 / REGION_W)
// pixels (16 x 4 strips or 8 x 8 quadrants, four warps per tile), each lane a pair of pixels
// in a row. Four warps per tile rather than FlashGS's one: the heaviest tiles (thousands of
// pairs) set the kernel's length, and a warp walks its list serially. Each warp walks its
// tile's list on its own, so it stops as soon as its own pixels are opaque, with no block
// barrier. Lanes load 32 Gaussians at once (coalesced id reads, independent attribute loads),
// stage them in shared memory and read them back as broadcasts. PIPELINED issues the next
// batch's loads before blending the current one, so their latency hides behind it.
// EXP2 (the FlashGS arithmetic; the kernel is issue-bound): each lane first tests the
// Gaussian it loaded against the region (exact ellipse-rectangle test of the alpha >= 1/255
// ellipse, with a margin over the blend's rounding), so the loop visits only Gaussians that
// can change one of the region's pixels; alpha = exp2 of log2 alpha as a polynomial in the
// pixel's offset (RegionGaussian), the 1/255 cut made on the exponent, FMAs throughout, no
// branch per pixel (at least one lane of the warp passes the cut on almost every visit, so a
// branch skipped nothing and cost its own instructions); a finished pixel's column becomes
// NaN, so later Gaussians change nothing there. The colour is summed by parts (ColourSteps).
// The stop rule's test runs only from the first staged Gaussian that might take a live pixel's
// T below the minimum, and the 0.99 clamp only in batches with a Gaussian that might reach it
// (both bounded per batch from each Gaussian's largest alpha over the region). Otherwise the
// arithmetic is the CPU's: the same alpha to ~1e-5, and its cut, clamp and stop rule.
// Only the Gaussians that meet the region are staged, packed in list order, so the loop over
// them is a counted one. Binned frames (BinGrid): the 4 blocks of a bin blend its tiles, each
// from its own tile list (FrameBuffers::tile_lists).
// HALF (EXP2 only; RenderOptions::fp16_blend): the staged Gaussians as HalfRegionGaussian and
// each lane's pixels as one half2, with no stop rule per Gaussian (see blend_region_gaussian_half).
template <int REGION_W, bool PIPELINED, bool EXP2, bool HALF, bool SURFACE>
__global__ void __launch_bounds__(kWarpsPerBlock * kWarp, kBlendBlocksPerSm) blend_warp_tile_kernel(BlendArgs a) {
  static_assert(EXP2 || !HALF, "the half blend is an exp2 blend");
  static_assert(!HALF || kLanePixelsX == 2, "a lane's pixels are one half2");
  constexpr int kRegionH = 64 / REGION_W;
  constexpr int kLanesX = REGION_W / kLanePixelsX;
  constexpr int kRegionsX = kTile / REGION_W;
  using Staged =
      std::conditional_t<HALF, HalfRegionGaussian, std::conditional_t<EXP2, RegionGaussian<kRegionH>, BlendGaussian>>;
  __shared__ Staged batch[kWarpsPerBlock][kWarp];
  const unsigned warp = threadIdx.x / kWarp, lane = lane_id();
  // A block is one tile, its warps the tile's regions.
  static_assert(kWarpsPerBlock == kRegionsPerTile, "a block must be one tile");
  const int shift = a.bins.shift;
  const unsigned block_bin = blockIdx.x >> (2 * shift);
  const unsigned bin = a.tile_order ? a.tile_order[block_bin] : block_bin;
  if (bin >= static_cast<unsigned>(a.bins.x) * static_cast<unsigned>(a.bins.y)) return;  // whole block
  const unsigned tile_in_bin = blockIdx.x & ((1u << (2 * shift)) - 1u);
  const int tx = static_cast<int>(bin % a.bins.x) * (1 << shift) + static_cast<int>(tile_in_bin & ((1u << shift) - 1u));
  const int ty = static_cast<int>(bin / a.bins.x) * (1 << shift) + static_cast<int>(tile_in_bin >> shift);
  if (tx >= a.tiles_x || ty >= a.tiles_y) return;  // a bin over the image's edge: whole block
  if (a.bins_ready) {  // launched beside the bin blocks: wait for this bin's lists
    if (threadIdx.x == 0)
      while (load_acquire(a.bins_ready + bin) != a.frame_tag) __nanosleep(200);
    __syncthreads();
  }
  const int region_in_tile = static_cast<int>(warp);
  // The region's pixel-centre rectangle, clipped to the image, and this lane's pixels.
  const float region_x0 = static_cast<float>(tx * kTile + (region_in_tile % kRegionsX) * REGION_W);
  const float region_y0 = static_cast<float>(ty * kTile + (region_in_tile / kRegionsX) * kRegionH);
  const float region_x1 = fminf(region_x0 + (REGION_W - 1), static_cast<float>(a.width - 1));
  const float region_y1 = fminf(region_y0 + (kRegionH - 1), static_cast<float>(a.height - 1));
  const float region_mid_y = region_y0 + 0.5f * (kRegionH - 1), region_half_h = 0.5f * (kRegionH - 1);
  const int x0 = static_cast<int>(region_x0) + static_cast<int>(lane % kLanesX) * kLanePixelsX;
  const int y = static_cast<int>(region_y0) + static_cast<int>(lane / kLanesX);
  // EXP2: the lane's pixels relative to the region's centre (the polynomial's origin).
  const float region_mid_x = region_x0 + 0.5f * (REGION_W - 1);
  float lane_x[kLanePixelsX];
  const float lane_y = static_cast<float>(y) - region_mid_y;
  const unsigned lane_row = lane / kLanesX;  // EXP2: the row of RegionGaussian::row
  float t[kLanePixelsX], cr[kLanePixelsX], cg[kLanePixelsX], cb[kLanePixelsX];
  unsigned live = 0;  // bit p: pixel p still blending
#pragma unroll
  for (int p = 0; p < kLanePixelsX; ++p) {
    cr[p] = cg[p] = cb[p] = 0.0f;
    t[p] = 1.0f;
    if (x0 + p < a.width && y < a.height) live |= 1u << p;
    lane_x[p] = !EXP2 || (live & (1u << p)) ? static_cast<float>(x0 + p) - region_mid_x : finished_column();
  }
  const unsigned inside = live;
  // HALF: the lane's pixels as one half2 (a column outside the image NaN, as above).
  const __half2 lane_x2 = __floats2half2_rn(lane_x[0], lane_x[1]), lane_y2 = __float2half2_rn(lane_y);
  const __half2 half_cut = __float2half2_rn(kLog2AlphaMin), half_alpha_max = __float2half2_rn(gm::kAlphaMax);
  __half2 t2 = __float2half2_rn(1.0f), cr2 = __float2half2_rn(0.0f), cg2 = cr2, cb2 = cr2;
  ColourSteps steps;  // EXP2, not HALF: cr, cg, cb sum colour steps
  TileList list;
  if (shift > 0) {
    const uint2 range = a.tile_lists[static_cast<unsigned>(ty) * static_cast<unsigned>(a.tiles_x) + static_cast<unsigned>(tx)];
    list = TileList{(tile_in_bin >> shift) ? a.tile_values[1] : a.tile_values[0], range.x, range.y};
  } else {
    const uint2 range = a.tile_ranges[bin];
    list = TileList{a.values, range.x, range.y};
  }
  // This batch's records (n of them, lane j the j-th) and, PIPELINED, their Gaussians, and the
  // next batch's records: read a batch early, so that loading its Gaussians waits for no read.
  unsigned record = 0;
  unsigned n = list.take(lane, record);
  BlendGaussian next{};
  if (PIPELINED && lane < n) next = load_gaussian(a.gaussians + record);
  unsigned ahead_record = 0, ahead_n = 0;
  if (PIPELINED) ahead_n = list.take(lane, ahead_record);
  while (n > 0) {
    if constexpr (HALF) {
      live = inside & ((__low2float(t2) >= gm::kTransmittanceMin ? 1u : 0u) |
                       (__high2float(t2) >= gm::kTransmittanceMin ? 2u : 0u));
    } else if constexpr (EXP2) {
      live = 0;
#pragma unroll
      for (int p = 0; p < kLanePixelsX; ++p) live |= isnan(lane_x[p]) ? 0u : 1u << p;
    }
    if (!__any_sync(kFullMask, live)) break;
    if (!PIPELINED && lane < n) next = load_gaussian(a.gaussians + record);
    __syncwarp();
    unsigned staged = n;  // Gaussians in batch[warp], in list order
    unsigned unstoppable = 0;  // EXP2: how many of them cannot stop a pixel
    bool clamp = true;         // EXP2: whether any of them needs the 0.99 clamp
    if constexpr (EXP2) {
      bool meets = false;
      const float cut = __fmaf_rn(next.opacity - kLog2AlphaMin, 1.00001f, 1e-4f);  // q' of alpha = 1/255
      const float conic_a = __fmaf_rn(next.w0, next.w0, next.w2 * next.w2);
      const float conic_b = __fmaf_rn(next.w0, next.w1, next.w2 * next.w3);
      const float conic_c = __fmaf_rn(next.w1, next.w1, next.w3 * next.w3);
      float q_min = 0.0f;
      if (lane < n && cut > 0.0f) {
        const float w[4] = {next.w0, next.w1, next.w2, next.w3};
        // Approximate divisions and fused arithmetic: the cut's margin covers their error (a
        // division's moves the edge minimiser along a flat valley, changing q to second order).
        q_min = gm::whitened_q_min_on_rect<true>(w, -conic_b * reciprocal_approx(conic_c),
                                                 -conic_b * reciprocal_approx(conic_a),
                                           region_x0 - next.mean_x, region_x1 - next.mean_x,
                                           region_y0 - next.mean_y, region_y1 - next.mean_y);
        meets = q_min <= cut;
      }
      const unsigned relevant = __ballot_sync(kFullMask, meets);
      float3 colour_step{};
      if constexpr (!HALF) {
        colour_step = steps.step(relevant, lane, next.red, next.green, next.blue);
        // Alpha is at most 2^(opacity - q_min) over the region (with a margin over the loop's
        // rounding): below 0.99, the clamp cannot act.
        clamp = __any_sync(kFullMask, meets && next.opacity - q_min + 1e-3f > kLog2AlphaMax);
      }
      // The stop rule can only act where T may fall below its minimum. At most, a staged
      // Gaussian leaves 1 - (its alpha at the region's nearest point) of a pixel's T (log2
      // alpha = opacity - q_min, with a margin over the loop's rounding), so the staged
      // Gaussians whose running product of these, times the lowest T of the warp's live
      // pixels, stays above 1.1 x the minimum (a margin over roundings of ~1e-7 each) cannot
      // stop a pixel: a prefix of the batch, cut to whole groups of the loop's unrolling. Near
      // the minimum, where almost any Gaussian might stop a pixel, the bound is not worth its scan.
      float lowest_t = INFINITY;
#pragma unroll
      for (int p = 0; p < kLanePixelsX; ++p) lowest_t = isnan(lane_x[p]) ? lowest_t : fminf(lowest_t, t[p]);
      // T > 0, so its bits order as the floats do.
      lowest_t = __uint_as_float(__reduce_min_sync(kFullMask, __float_as_uint(lowest_t)));
      if (!HALF && a.stop_bound && lowest_t >= kBoundWorthT) {
        float kept = meets ? 1.0f - fminf(gm::kAlphaMax, exp2_approx(next.opacity - q_min + 1e-3f)) : 1.0f;
#pragma unroll
        for (int offset = 1; offset < kWarp; offset <<= 1) {
          const float before = __shfl_up_sync(kFullMask, kept, offset);
          if (lane >= static_cast<unsigned>(offset)) kept *= before;
        }
        unstoppable = __popc(__ballot_sync(kFullMask, meets && lowest_t * kept >= 1.1f * gm::kTransmittanceMin));
        unstoppable &= ~static_cast<unsigned>(kBlendUnroll - 1);
      }
      if (meets) {
        // The whitened rows at the region's centre: (u0, v0), and log2 alpha there and around.
        const float ox = next.mean_x - region_mid_x, oy = next.mean_y - region_mid_y;
        const float u0 = -__fmaf_rn(next.w0, ox, next.w1 * oy), v0 = -__fmaf_rn(next.w2, ox, next.w3 * oy);
        Staged& slot = batch[warp][__popc(relevant & ((1u << lane) - 1u))];
        if constexpr (HALF)
          slot = HalfRegionGaussian{__floats2half2_rn(u0, v0), __floats2half2_rn(next.w1, next.w3),
                                    __floats2half2_rn(next.w0, next.w2), __floats2half2_rn(next.opacity, next.red),
                                    __floats2half2_rn(next.green, next.blue), {0u, 0u, 0u}};
        else
          slot = region_gaussian<kRegionH>(next, colour_step, u0, v0, conic_a, conic_b, conic_c);
      }
      staged = __popc(relevant);
    } else {
      batch[warp][lane] = next;
    }
    __syncwarp();
    unsigned next_record = 0, next_n = 0;
    if constexpr (PIPELINED) {
      next_record = ahead_record;
      next_n = ahead_n;
      if (lane < next_n) next = load_gaussian(a.gaussians + next_record);
      ahead_n = list.take(lane, ahead_record);
    } else {
      next_n = list.take(lane, next_record);
    }
    if constexpr (HALF) {
#pragma unroll kBlendUnroll
      for (unsigned j = 0; j < staged; ++j)
        blend_region_gaussian_half(batch[warp][j], lane_y2, lane_x2, half_cut, half_alpha_max, t2, cr2, cg2, cb2);
    } else if constexpr (EXP2) {
      if (clamp) blend_staged<true>(batch[warp], unstoppable, staged, lane_row, lane_x, t, cr, cg, cb);
      else blend_staged<false>(batch[warp], unstoppable, staged, lane_row, lane_x, t, cr, cg, cb);
    } else {
#pragma unroll kBlendUnroll
      for (unsigned j = 0; j < staged && live; ++j) {
        const Staged& g = batch[warp][j];
        // The whole region lies beyond the rows this Gaussian can reach: a warp-uniform skip.
        if (fabsf(region_mid_y - g.mean_y) > g.reach_y + region_half_h) continue;
        const float dy = static_cast<float>(y) - g.mean_y;
        const float uy = g.w1 * dy, vy = g.w3 * dy;
#pragma unroll
        for (int p = 0; p < kLanePixelsX; ++p) {
          if (!(live & (1u << p))) continue;
          const float dx = static_cast<float>(x0 + p) - g.mean_x;
          const float u = g.w0 * dx + uy, v = g.w2 * dx + vy;
          const float power = -0.5f * (u * u + v * v);
          const float alpha = fminf(gm::kAlphaMax, g.opacity * expf(power));
          if (alpha < gm::kAlphaMin) continue;
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
    n = next_n;
    record = next_record;
  }
  if constexpr (HALF) {
    const float2 t_out = __half22float2(t2), r_out = __half22float2(cr2), g_out = __half22float2(cg2),
                 b_out = __half22float2(cb2);
    t[0] = t_out.x, t[1] = t_out.y, cr[0] = r_out.x, cr[1] = r_out.y;
    cg[0] = g_out.x, cg[1] = g_out.y, cb[0] = b_out.x, cb[1] = b_out.y;
  }
  // The background takes what T is left; with colour steps, so does the last staged colour's removal.
  const float background[3] = {a.background[0] - steps.last_red, a.background[1] - steps.last_green,
                               a.background[2] - steps.last_blue};
#pragma unroll
  for (int p = 0; p < kLanePixelsX; ++p)
    if (inside & (1u << p))
      write_pixel<SURFACE>(a, x0 + p, y, cr[p] + t[p] * background[0], cg[p] + t[p] * background[1],
                           cb[p] + t[p] * background[2]);
}

// A block per tile of each bin (tiles of bins over the image's edge return at once). With
// bins_ready, the launch may start before the bin blocks before it in the stream have ended
// (programmatic dependent launch): each block waits for its own bin's lists instead.
template <int REGION_W, bool PIPELINED, bool EXP2, bool HALF, bool SURFACE>
void launch_warp_tile_kernel(const BlendArgs& a, cudaStream_t stream) {
  cudaLaunchConfig_t config{};
  config.gridDim = dim3(static_cast<unsigned>(a.bins.x) * static_cast<unsigned>(a.bins.y) << (2 * a.bins.shift));
  config.blockDim = dim3(kWarpsPerBlock * kWarp);
  config.stream = stream;
  cudaLaunchAttribute early{};
  early.id = cudaLaunchAttributeProgrammaticStreamSerialization;
  early.val.programmaticStreamSerializationAllowed = 1;
  if (a.bins_ready) {
    config.attrs = &early;
    config.numAttrs = 1;
  }
  check_cuda(cudaLaunchKernelEx(&config, blend_warp_tile_kernel<REGION_W, PIPELINED, EXP2, HALF, SURFACE>, a),
             "blend kernel launch");
}

template <int REGION_W, bool SURFACE>
void launch_warp_tile(const BlendArgs& a, cudaStream_t stream) {
  const bool pipelined = a.kernel == BlendKernel::warp_tile_pipelined;
  const bool half = a.exp2_alpha && a.half_blend;
  if (pipelined && half) launch_warp_tile_kernel<REGION_W, true, true, true, SURFACE>(a, stream);
  else if (pipelined && a.exp2_alpha) launch_warp_tile_kernel<REGION_W, true, true, false, SURFACE>(a, stream);
  else if (pipelined) launch_warp_tile_kernel<REGION_W, true, false, false, SURFACE>(a, stream);
  else if (half) launch_warp_tile_kernel<REGION_W, false, true, true, SURFACE>(a, stream);
  else if (a.exp2_alpha) launch_warp_tile_kernel<REGION_W, false, true, false, SURFACE>(a, stream);
  else launch_warp_tile_kernel<REGION_W, false, false, false, SURFACE>(a, stream);
}


template <bool SURFACE>
void launch_for_output(const BlendArgs& a, cudaStream_t stream) {
  const unsigned tiles = static_cast<unsigned>(a.tiles_x) * static_cast<unsigned>(a.tiles_y);
  if (a.kernel == BlendKernel::per_pixel) {
    blend_per_pixel_kernel<SURFACE><<<tiles, kTile * kTile, 0, stream>>>(a);
    return;
  }
  if (a.region_width == 16) launch_warp_tile<16, SURFACE>(a, stream);
  else launch_warp_tile<8, SURFACE>(a, stream);
}

}  // namespace

std::uint64_t blend_resident_blocks() {
  int device = 0, sms = 0, per_sm = 0;
  check_cuda(cudaGetDevice(&device), "device query");
  check_cuda(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, device), "device query");
  check_cuda(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_sm, blend_warp_tile_kernel<8, true, true, false, false>,
                                                           kWarpsPerBlock * kWarp, 0),
             "occupancy query");
  return static_cast<std::uint64_t>(std::max(1, sms * per_sm));
}

void launch_blend(const BlendArgs& args, cudaStream_t stream) {
  if (args.image_rgb) launch_for_output<false>(args, stream);
  else launch_for_output<true>(args, stream);
  check_cuda(cudaGetLastError(), "blend kernel launch");
}

}  // namespace cuda
}  // namespace flashgs
