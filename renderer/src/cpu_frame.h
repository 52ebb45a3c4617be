// Working memory and stage functions of the CPU backend (internal to renderer/).
#pragma once

#include <cstdint>
#include <vector>

#include "flashgs/gaussian_math.h"
#include "flashgs/options.h"
#include "flashgs/scene.h"
#include "flashgs/stats.h"

namespace flashgs {
namespace cpu {

// What the blend stage reads per Gaussian, packed so one cache line serves one Gaussian.
struct BlendGaussian {
  float mean_x, mean_y;
  float whiten[4];  // q = (w0 dx + w1 dy)^2 + (w2 dx + w3 dy)^2 (gm::Footprint::whiten)
  float opacity;
  float rgb[3];
  // Below this power, alpha < 1/255 for certain (a margin keeps the exact test authoritative).
  float power_cut;
  // Row pruning: over a row at offset dy the smallest q is row_q_coeff * dy^2, reached at
  // dx = row_slope * dy (= -conic_b / conic_a * dy); pixels farther than
  // sqrt((q_cut - q) * inv_conic_a) from it cannot pass power_cut.
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

  // Emission: each thread's pairs (tile, key) for its static chunk of Gaussians, and its
  // per-tile histogram. key = depth bits << 32 | Gaussian id. Only the first emit_chunks
  // entries (the team the emit region was granted) belong to this frame.
  int emit_chunks = 0;
  std::vector<std::vector<std::uint32_t>> thread_tiles;
  std::vector<std::vector<std::uint64_t>> thread_keys;
  std::vector<std::vector<std::uint32_t>> thread_tile_counts;  // [thread][tile]

  std::vector<std::uint64_t> tile_start;   // [tiles + 1] offsets into sorted_keys
  std::vector<std::uint64_t> sorted_keys;  // [pairs], tile-major, (depth, id) within a tile
};

void project(const Scene& scene, const RenderOptions& options, Frame& frame, FrameStats& stats);
void emit(const Scene& scene, const RenderOptions& options, Frame& frame, FrameStats& stats);
// Sorts by tile, then depth, then Gaussian id; fills tile_start (the ranges stage).
void sort_by_tile(Frame& frame, FrameStats& stats, double* ranges_ms);
void blend(const RenderOptions& options, Frame& frame, float* rgb);

}  // namespace cpu
}  // namespace flashgs
