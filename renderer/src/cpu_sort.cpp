// CPU sort and ranges stages: counting sort by tile, then each tile's keys by (depth, id).
#include <algorithm>
#include <chrono>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "cpu_frame.h"
#include "parallel_errors.h"

namespace flashgs {
namespace cpu {

namespace {

// Below this many keys an insertion sort beats the radix passes' bucket tables.
constexpr std::size_t kInsertionSortBelow = 48;

// Sorts a tile's keys (depth bits << 32 | id) into (depth, id) order. They arrive in ascending
// id order (emit's chunks in thread order, each in id order), so a stable sort by the depth
// bits alone gives that order: an LSD radix sort on the 4 depth bytes, skipping a byte every
// key shares (most tiles' depths share their exponent byte). `scratch` only grows.
void sort_tile_keys(std::uint64_t* keys, std::size_t n, std::vector<std::uint64_t>& scratch) {
  if (n < kInsertionSortBelow) {
    for (std::size_t i = 1; i < n; ++i) {
      const std::uint64_t key = keys[i];
      std::size_t j = i;
      for (; j > 0 && keys[j - 1] > key; --j) keys[j] = keys[j - 1];
      keys[j] = key;
    }
    return;
  }
  std::uint32_t counts[4][256] = {};
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t depth = static_cast<std::uint32_t>(keys[i] >> 32);
    for (int b = 0; b < 4; ++b) counts[b][(depth >> (8 * b)) & 255]++;
  }
  if (scratch.size() < n) scratch.resize(n);
  std::uint64_t* from = keys;
  std::uint64_t* to = scratch.data();
  for (int b = 0; b < 4; ++b) {
    const int shift = 32 + 8 * b;
    if (counts[b][(from[0] >> shift) & 255] == n) continue;  // every key has this byte
    std::uint32_t start[256];
    std::uint32_t running = 0;
    for (int digit = 0; digit < 256; ++digit) {
      start[digit] = running;
      running += counts[b][digit];
    }
    for (std::size_t i = 0; i < n; ++i) to[start[(from[i] >> shift) & 255]++] = from[i];
    std::swap(from, to);
  }
  if (from != keys) std::copy(from, from + n, keys);
}

}  // namespace

void sort_by_tile(Frame& frame, FrameStats& stats, double* ranges_ms) {
  using Clock = std::chrono::steady_clock;
  const int chunks = frame.emit_chunks;  // the emit stage's pair lists
  const std::size_t tiles = static_cast<std::size_t>(frame.camera.tiles_x) * frame.camera.tiles_y;

  // Ranges: each chunk's histogram becomes its write cursor within each tile (the pairs of
  // earlier chunks first), tile_start[tile + 1] the tile's total, then a scan of the totals.
  const auto ranges_begin = Clock::now();
  frame.tile_start.assign(tiles + 1, 0);
  std::uint64_t* tile_start = frame.tile_start.data();
  constexpr std::int64_t kTilesPerTask = 1024;
  const std::int64_t tasks = (static_cast<std::int64_t>(tiles) + kTilesPerTask - 1) / kTilesPerTask;
  // In parallel only when there is enough to share: a parallel region's start and barrier
  // cost more than a few ten thousand additions (a 1080p frame's 8160 tiles x 16 chunks on 2
  // threads took 0.14 ms alone, 128 chunks on 16 threads 0.93 ms, on the H200 host).
  const bool share = static_cast<std::uint64_t>(tiles) * static_cast<std::uint64_t>(chunks) > (1u << 16);
#pragma omp parallel for schedule(static) num_threads(frame.threads) if (share)
  for (std::int64_t task = 0; task < tasks; ++task) {
    const std::size_t begin = static_cast<std::size_t>(task * kTilesPerTask);
    const std::size_t end = std::min(tiles, begin + static_cast<std::size_t>(kTilesPerTask));
    for (int c = 0; c < chunks; ++c) {
      std::uint32_t* counts = frame.chunk_tile_counts[c].data();
      for (std::size_t tile = begin; tile < end; ++tile) {
        const std::uint32_t count = counts[tile];
        counts[tile] = static_cast<std::uint32_t>(tile_start[tile + 1]);
        tile_start[tile + 1] += count;
      }
    }
  }
  for (std::size_t tile = 0; tile < tiles; ++tile) tile_start[tile + 1] += tile_start[tile];
  const std::uint64_t pairs = tile_start[tiles];
  *ranges_ms = std::chrono::duration<double, std::milli>(Clock::now() - ranges_begin).count();

  if (frame.sorted_keys.size() < pairs) frame.sorted_keys.resize(pairs);
  std::uint64_t* sorted = frame.sorted_keys.data();
  ParallelErrors errors;
#pragma omp parallel for schedule(dynamic, 1) num_threads(frame.threads)
  for (int c = 0; c < chunks; ++c)
    errors.capture([&] {
      const std::vector<std::uint32_t>& tile_of = frame.chunk_tiles[c];
      const std::vector<std::uint64_t>& keys = frame.chunk_keys[c];
      std::uint32_t* cursor = frame.chunk_tile_counts[c].data();
      for (std::size_t k = 0; k < keys.size(); ++k) {
        const std::uint32_t tile = tile_of[k];
        sorted[tile_start[tile] + cursor[tile]++] = keys[k];
      }
    });
  errors.rethrow();
  // The key holds the Gaussian id below the depth, so equal depths sort by id: the order,
  // and the image, do not depend on how the work was split.
  if (frame.sort_scratch.size() < static_cast<std::size_t>(frame.threads)) frame.sort_scratch.resize(frame.threads);
  const std::int64_t tile_count = static_cast<std::int64_t>(tiles);
#pragma omp parallel for schedule(dynamic, 16) num_threads(frame.threads)
  for (std::int64_t tile = 0; tile < tile_count; ++tile)
    errors.capture([&] {
#ifdef _OPENMP
      const int thread = omp_get_thread_num();
#else
      const int thread = 0;
#endif
      const std::uint64_t begin = frame.tile_start[tile], end = frame.tile_start[tile + 1];
      sort_tile_keys(sorted + begin, end - begin, frame.sort_scratch[thread]);
    });
  errors.rethrow();

  stats.max_tile_pairs = 0;
  for (std::size_t tile = 0; tile < tiles; ++tile)
    stats.max_tile_pairs = std::max<std::uint32_t>(
        stats.max_tile_pairs, static_cast<std::uint32_t>(frame.tile_start[tile + 1] - frame.tile_start[tile]));
}

}  // namespace cpu
}  // namespace flashgs
