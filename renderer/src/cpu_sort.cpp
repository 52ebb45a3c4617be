// CPU sort and ranges stages: counting sort by tile, then each tile's keys by (depth, id).
#include <algorithm>
#include <chrono>

#include "cpu_frame.h"
#include "parallel_errors.h"

namespace flashgs {
namespace cpu {

void sort_by_tile(Frame& frame, FrameStats& stats, double* ranges_ms) {
  using Clock = std::chrono::steady_clock;
  const int chunks = frame.emit_chunks;  // the emit stage's per-thread pair lists
  const std::size_t tiles = static_cast<std::size_t>(frame.camera.tiles_x) * frame.camera.tiles_y;

  // Ranges: tile_start from the per-thread histograms, and each thread's write cursor per tile.
  const auto ranges_begin = Clock::now();
  frame.tile_start.assign(tiles + 1, 0);
  std::uint64_t running = 0;
  for (std::size_t tile = 0; tile < tiles; ++tile) {
    frame.tile_start[tile] = running;
    for (int t = 0; t < chunks; ++t) {
      const std::uint32_t c = frame.thread_tile_counts[t][tile];
      frame.thread_tile_counts[t][tile] = static_cast<std::uint32_t>(running - frame.tile_start[tile]);
      running += c;
    }
  }
  frame.tile_start[tiles] = running;
  *ranges_ms = std::chrono::duration<double, std::milli>(Clock::now() - ranges_begin).count();

  if (frame.sorted_keys.size() < running) frame.sorted_keys.resize(running);
  std::uint64_t* sorted = frame.sorted_keys.data();
  ParallelErrors errors;
#pragma omp parallel for schedule(static, 1) num_threads(frame.threads)
  for (int t = 0; t < chunks; ++t)
    errors.capture([&] {
      const std::vector<std::uint32_t>& tile_of = frame.thread_tiles[t];
      const std::vector<std::uint64_t>& keys = frame.thread_keys[t];
      std::vector<std::uint32_t>& cursor = frame.thread_tile_counts[t];
      for (std::size_t k = 0; k < keys.size(); ++k) {
        const std::uint32_t tile = tile_of[k];
        sorted[frame.tile_start[tile] + cursor[tile]++] = keys[k];
      }
    });
  errors.rethrow();
  // The key holds the Gaussian id below the depth, so equal depths sort by id: the order,
  // and the image, do not depend on how the work was split.
  const std::int64_t tile_count = static_cast<std::int64_t>(tiles);
#pragma omp parallel for schedule(dynamic, 16) num_threads(frame.threads)
  for (std::int64_t tile = 0; tile < tile_count; ++tile)
    errors.capture([&] { std::sort(sorted + frame.tile_start[tile], sorted + frame.tile_start[tile + 1]); });
  errors.rethrow();

  stats.max_tile_pairs = 0;
  for (std::size_t tile = 0; tile < tiles; ++tile)
    stats.max_tile_pairs = std::max<std::uint32_t>(
        stats.max_tile_pairs, static_cast<std::uint32_t>(frame.tile_start[tile + 1] - frame.tile_start[tile]));
}

}  // namespace cpu
}  // namespace flashgs
