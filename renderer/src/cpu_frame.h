// Working memory and stage functions of the CPU backend (internal to renderer/).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "flashgs/gaussian_math.h"
#include "flashgs/options.h"
#include "flashgs/scene.h"
#include "flashgs/stats.h"

namespace flashgs {
namespace cpu {

// What the blend stage reads per Gaussian: 16 floats on one cache line (aligned to it).
struct alignas(64) BlendGaussian {
  float mean_x, mean_y;
  float whiten[4];  // q = (w0 dx + w1 dy)^2 + (w2 dx + w3 dy)^2 (gm::Footprint::whiten)
  float opacity;
  float rgb[3];
  float log2_opacity;  // the SIMD kernel's alpha is 2^(q * -log2(e) / 2 + log2_opacity)
  // Row pruning: over a row at offset dy the smallest q is row_q_coeff * dy^2, reached at
  // dx = row_slope * dy (= -conic_b / conic_a * dy); pixels farther than
  // sqrt((q_cut - q) * inv_conic_a) from it cannot pass power_cut = -q_cut / 2, below which
  // alpha < 1/255 for certain (a margin keeps the exact test authoritative).
  float row_q_coeff;
  float q_cut;
  float row_slope;
  float inv_conic_a;
};

// Reused from frame to frame; vectors only grow (high-water mark), nothing is freed.
struct Frame {
  gm::CameraParams camera{};
  gm::GeometryParams geometry{};
  int threads = 1;

  std::vector<gm::Footprint> footprints;   // [gaussians]
  std::vector<std::uint8_t> cull;          // [gaussians] gm::CullReason
  std::vector<BlendGaussian> blend_data;   // [gaussians]
  // [gaussians] gm::depth_bits of a visible Gaussian's depth: the depth sort reads these 4 bytes
  // instead of a footprint's cache line
  std::vector<std::uint32_t> depth_bits;
  // RenderOptions::fp16_sh: the SH of scene `half_sh_of` rounded to halves, made by its first
  // such frame (the renderer resets half_sh_of with the scene).
  const Scene* half_sh_of = nullptr;
  std::vector<float> half_sh_dc, half_sh_rest;
  // RenderOptions::fp16_shape: the rotations, scales and opacities of scene `half_shape_of`
  // rounded to halves, made by its first such frame (reset with the scene as above).
  const Scene* half_shape_of = nullptr;
  std::vector<float> half_rotations, half_scales, half_opacities;
  // BlendGaussian's opacity-only terms (log2_opacity, q_cut) of the `opacity_terms_size`
  // opacities at `opacity_terms_of` (the scene's or their halves), made by the first frame that
  // reads them (the renderer resets it with the scene).
  const float* opacity_terms_of = nullptr;
  std::size_t opacity_terms_size = 0;
  std::vector<float> log2_opacity, q_cut;  // [gaussians]

  // The visible Gaussians as keys (depth bits << 32 | id), in (depth, id) order after
  // order_by_depth: depth_order points at visible_count of them (project counts them), in
  // depth_keys or depth_scratch (whichever the last radix pass wrote), which have room for the
  // most Gaussians a frame had in view.
  std::vector<std::uint64_t> depth_keys, depth_scratch;
  std::vector<std::uint32_t> depth_slice_counts;  // [threads][256] the radix passes' digit counts
  const std::uint64_t* depth_order = nullptr;
  std::size_t visible_count = 0;

  // Emission: the pairs (tile, Gaussian id) of each chunk (emit_chunk_count) of consecutive
  // Gaussians of the depth order, and the chunk's per-tile histogram (then, after sort_by_tile's
  // ranges, its write cursor per tile). Only the first emit_chunks entries belong to this frame.
  int emit_chunks = 0;
  std::vector<std::vector<std::uint32_t>> chunk_tiles;
  std::vector<std::vector<std::uint32_t>> chunk_ids;
  std::vector<std::vector<std::uint32_t>> chunk_tile_counts;  // [chunk][tile]

  std::vector<std::uint64_t> tile_start;  // [tiles + 1] offsets into tile_ids
  std::vector<std::uint32_t> tile_ids;    // [pairs] Gaussian ids, tile-major, (depth, id) order within a tile

  std::vector<std::uint32_t> tile_order;  // [tiles] the blend's schedule: longest pair counts first
};

// How many chunks emit splits `visible` Gaussians into on `threads` threads: several per thread,
// taken dynamically, since a scene's pairs are far from even along its Gaussians (pc_playbot's
// sixteenths in id order hold 2k to 152k pairs of one view) and equal static shares left
// threads idle; at least 4096 Gaussians each.
inline int emit_chunk_count(int threads, std::uint64_t visible) {
  constexpr std::uint64_t kChunksPerThread = 8, kMinChunkGaussians = 4096;
  const std::uint64_t most = static_cast<std::uint64_t>(threads > 1 ? threads : 1) * kChunksPerThread;
  return static_cast<int>(std::max<std::uint64_t>(1, std::min(most, visible / kMinChunkGaussians)));
}

// One tile for a blend kernel: its Gaussians in blend order and where it lies in the image.
struct TileJob {
  const std::uint32_t* ids;
  std::uint64_t count;
  int tile_x, tile_y;
  const float* background;  // [3]
};

// The per-Gaussian arrays the project stage reads: the scene's, or under the fp16 options their
// half values (Frame's copies). Layouts as in Scene.
struct SceneArrays {
  std::int64_t count;
  const float* positions;  // [count][3]
  const float* scales;     // [count][3]
  const float* rotations;  // [count][4]
  const float* opacities;  // [count]
  const float* dc;         // [count][3]
  const float* rest;       // [count][rest_n]
  int rest_n;
};

// BlendGaussian's opacity-only terms of an opacity: log2_opacity, and q_cut (power_cut = -q_cut / 2
// exactly, with a margin below alpha = 1/255).
inline void opacity_terms(float opacity, float& log2_opacity, float& q_cut) {
  const float power_cut = opacity > 0 ? std::log(gm::kAlphaMin / opacity) - 1e-3f : 0.0f;
  log2_opacity = std::log2(opacity);
  q_cut = -2.0f * power_cut;
}

// BlendGaussian's opacity and its terms for visible Gaussian `i` drawn at `opacity`
// (Footprint::opacity): the per-scene cache where that is the scene's opacity (the classic
// kernel), else computed here (the anti-aliased kernel's opacity depends on the view).
inline void set_opacity_terms(const Frame& frame, std::int64_t i, float opacity, BlendGaussian& g) {
  g.opacity = opacity;
  if (frame.geometry.compensate_opacity) {
    // One logarithm per visible Gaussian, not two (the classic cache's log2 and log): this runs
    // every frame. log2 o = ln o * log2(e) is within an ulp of it, far inside the SIMD alpha's bound.
    const float ln_opacity = opacity > 0 ? std::log(opacity) : -INFINITY;
    g.log2_opacity = ln_opacity * 1.44269504f;
    const float power_cut = opacity > 0 ? std::log(gm::kAlphaMin) - ln_opacity - 1e-3f : 0.0f;
    g.q_cut = -2.0f * power_cut;
  } else {
    g.log2_opacity = frame.log2_opacity[i];
    g.q_cut = frame.q_cut[i];
  }
}

// Which kernel projects: both give the same bytes (the SIMD one runs gm::project's operations
// per lane, in its order); the scalar one is the reference the tests compare with.
enum class ProjectKernel { simd, scalar };
void project(const Scene& scene, const RenderOptions& options, Frame& frame, FrameStats& stats,
             ProjectKernel kernel = ProjectKernel::simd);
// Projects Gaussians [begin, end) of `scene` into frame.footprints, cull and blend_data;
// `degree` is the SH bands used. The scalar reference (cpu_project.cpp) and the SIMD kernel
// (cpu_project_simd.cpp; without Highway it is the scalar one).
void project_block_scalar(const SceneArrays& scene, int degree, Frame& frame, std::int64_t begin, std::int64_t end);
void project_block_simd(const SceneArrays& scene, int degree, Frame& frame, std::int64_t begin, std::int64_t end);
// BlendGaussian's row-pruning terms from its whitened rows, in double: (a c - b^2) / a =
// det(W)^2 / a (Lagrange's identity); det(W) = w0 w3 - w1 w2 adds two non-negative terms, so a
// needle (a nearly singular conic) keeps an accurate row minimum.
inline void set_row_pruning(BlendGaussian& g) {
  const double w0 = g.whiten[0], w1 = g.whiten[1], w2 = g.whiten[2], w3 = g.whiten[3];
  const double conic_a = w0 * w0 + w2 * w2, det_w = w0 * w3 - w1 * w2;
  g.row_q_coeff = static_cast<float>(det_w * det_w / conic_a);
  g.row_slope = static_cast<float>(-(w0 * w1 + w2 * w3) / conic_a);
  g.inv_conic_a = static_cast<float>(1.0 / conic_a);
}
// Puts the visible Gaussians (cull == kVisible) of the first `gaussians` in (depth, id) order:
// depth_order (visible_count of them, as project counted). Part of the sort stage, run before emit.
void order_by_depth(Frame& frame, std::int64_t gaussians);
// The same on `threads` threads, however many processors there are (the tests' uneven splits).
void order_by_depth_on(Frame& frame, std::int64_t gaussians, int threads);
// Throws flashgs::Error, with the figures, when the pairs emit would make for the visible
// Gaussians (counted from their boxes; for the exact tile test, estimated from a sample of
// them) cannot fit in the memory available. Run after order_by_depth, before emit.
void check_pairs_fit(const RenderOptions& options, const Frame& frame);
// Emits the pairs of the visible Gaussians, walking them in depth order.
void emit(const RenderOptions& options, Frame& frame, FrameStats& stats);
// The tiles of f's box that gm::footprint_touches_tile keeps, as tile indices in row-major
// order, into out, which must hold exact_box_tiles_room(f) values; returns how many
// (cpu_emit_simd.cpp: a vector of tiles at a time, the scalar test's decisions).
std::size_t exact_box_tiles(const gm::Footprint& f, int width, int height, int tiles_x, std::uint32_t* out);
std::size_t exact_box_tiles_room(const gm::Footprint& f);
// Puts emit's pairs in tile order, keeping their (depth, id) order within a tile: tile_ids and
// tile_start (the ranges stage).
void sort_by_tile(Frame& frame, FrameStats& stats, double* ranges_ms);
// Which kernel composites the tiles. simd_unpruned: the SIMD kernel with row spans that hold
// the whole tile (every Gaussian of a tile visits every live row; slow), for the tests, which
// check that the spans change no byte.
enum class BlendKernel { simd, scalar, simd_unpruned };
// Where the scalar kernel writes the debug planes (FrameStats::pixel_depth, pixel_blended),
// each width x height.
struct PixelPlanes {
  float* depth;
  std::uint32_t* blended;
};
// Blends every tile, densest first. `cancelled` is asked between tiles; once it says yes the
// remaining tiles are left as they are and blend returns false. With `planes` every tile runs
// the scalar kernel, which fills them too.
bool blend(const RenderOptions& options, Frame& frame, BlendKernel kernel, const std::function<bool()>& cancelled,
           float* rgb, const PixelPlanes* planes = nullptr);
// The scalar reference kernel (cpu_blend_scalar.cpp) and the SIMD one (cpu_blend_simd.cpp;
// without Highway it is the scalar one). Both write the tile's pixels of `rgb`; the scalar one
// also those of `planes` where given.
void blend_tile_scalar(const Frame& frame, const TileJob& tile, float* rgb, const PixelPlanes* planes = nullptr);
enum class SpanPruning { on, off };
void blend_tile_simd(const Frame& frame, const TileJob& tile, float* rgb, SpanPruning pruning = SpanPruning::on);
// The SIMD kernel's alpha before its 0.99 cap, opacity e^(-q/2) computed as 2^(q * -log2(e)/2 +
// log2_opacity), for n lanes (the tests check its bound on every target). Its relative error
// against the exact value is below kSimdAlphaMaxRelError wherever alpha >= 1/255, and it is
// below 1/255 wherever the exact value is below 1/255 e^-0.001 (power_cut's margin).
void simd_alpha(const float* q, const float* log2_opacity, float* alpha, std::size_t n);
constexpr double kSimdAlphaMaxRelError = 4e-6;
// The SIMD target blend_tile_simd runs on this CPU ("AVX2", "AVX3", ...; "scalar" without Highway).
std::string simd_target_name();
// `wanted` (the cpu_simd knob, BackendTuning) names the best target the SIMD kernels may use
// (e.g. AVX2 on an AVX-512 host, to measure what most desktops run); empty, the CPU's best. A
// name this build or CPU lacks gets one line on stderr and the best target. Applies to the
// whole process.
void apply_simd_target_limit(const std::string& wanted);

}  // namespace cpu
}  // namespace flashgs
