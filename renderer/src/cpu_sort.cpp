// CPU sort and ranges stages. The visible Gaussians are put in (depth, id) order once per frame
// (order_by_depth, before emit); emit walks them in that order, so each tile's pairs come out in
// blend order and a stable counting sort by tile (sort_by_tile, after emit) is all that is left:
// no per-tile sorts. On pc_playbot at 1080p (2 threads of a Zen 4 VM) that is ~400k keys sorted
// once instead of 1.55M pairs sorted per tile.
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

#ifdef _OPENMP
int thread_index() { return omp_get_thread_num(); }
int team_size() { return omp_get_num_threads(); }
int processors() { return omp_get_num_procs(); }
#else
int thread_index() { return 0; }
int team_size() { return 1; }
int processors() { return 1; }
#endif

constexpr int kDigitBits = 8;
constexpr int kDigits = 1 << kDigitBits;
constexpr int kDepthDigits = 32 / kDigitBits;

// [begin, end) of slice `slice` of `count` items cut into `slices` nearly equal parts.
std::size_t slice_begin(std::size_t count, int slice, int slices) {
  return count * static_cast<std::size_t>(slice) / static_cast<std::size_t>(slices);
}

}  // namespace

void order_by_depth(Frame& frame, std::int64_t gaussians) {
  // The passes meet at barriers, so at most one thread per processor: more (--threads above the
  // core count) would wait at each barrier for threads that are not running (pc_playbot 1080p,
  // 64 threads on 2 cores: sort 14.2 ms against 9.4 for the per-tile sorts before, 10.4 capped).
  order_by_depth_on(frame, gaussians, std::max(1, std::min(frame.threads, processors())));
}

void order_by_depth_on(Frame& frame, std::int64_t gaussians, int threads) {
  const std::size_t n = static_cast<std::size_t>(gaussians);
  frame.depth_slice_counts.assign(static_cast<std::size_t>(threads) * kDigits, 0);
  // Room for the Gaussians in view, not the scene: project counted them (grown only).
  if (frame.depth_keys.size() < frame.visible_count) {
    frame.depth_keys.resize(frame.visible_count);
    frame.depth_scratch.resize(frame.visible_count);
  }
  std::size_t visible = 0;
  // One parallel region: the key list, then an LSD radix sort on the four depth bytes, each pass
  // stable (a thread's slice of keys goes, in order, after the earlier slices' keys of the same
  // digit). The keys start in id order, so equal depths end in id order: the order, and the
  // image, do not depend on the thread count.
#pragma omp parallel num_threads(threads)
  {
    const int t = thread_index(), slices = team_size();
    std::uint32_t* counts = frame.depth_slice_counts.data() + static_cast<std::size_t>(t) * kDigits;
    const std::uint8_t* cull = frame.cull.data();
    const std::size_t id_begin = slice_begin(n, t, slices), id_end = slice_begin(n, t + 1, slices);
    std::uint32_t mine = 0;
    for (std::size_t i = id_begin; i < id_end; ++i) mine += cull[i] == gm::kVisible;
    counts[0] = mine;
#pragma omp barrier
    std::size_t write = 0;
    for (int s = 0; s < t; ++s) write += frame.depth_slice_counts[static_cast<std::size_t>(s) * kDigits];
    std::uint64_t* keys = frame.depth_keys.data();
    const std::uint32_t* depth_bits = frame.depth_bits.data();
    for (std::size_t i = id_begin; i < id_end; ++i)
      if (cull[i] == gm::kVisible)
        keys[write++] = (static_cast<std::uint64_t>(depth_bits[i]) << 32) | i;
    if (t == slices - 1) visible = write;
#pragma omp barrier

    std::uint64_t* from = frame.depth_keys.data();
    std::uint64_t* to = frame.depth_scratch.data();
    const std::size_t key_begin = slice_begin(visible, t, slices), key_end = slice_begin(visible, t + 1, slices);
    for (int digit = 0; digit < kDepthDigits; ++digit) {
      const int shift = 32 + kDigitBits * digit;
      std::fill(counts, counts + kDigits, 0u);
      for (std::size_t k = key_begin; k < key_end; ++k) counts[(from[k] >> shift) & (kDigits - 1)]++;
#pragma omp barrier
      // Each thread turns the counts into its own write cursors: digit-major, then slice order.
      std::size_t cursor[kDigits];
      std::size_t running = 0, shared_by_all = 0;
      for (int d = 0; d < kDigits; ++d) {
        std::size_t digit_total = 0;
        for (int s = 0; s < slices; ++s) {
          const std::uint32_t c = frame.depth_slice_counts[static_cast<std::size_t>(s) * kDigits + d];
          if (s == t) cursor[d] = running + digit_total;
          digit_total += c;
        }
        running += digit_total;
        shared_by_all = std::max(shared_by_all, digit_total);
      }
      if (shared_by_all == visible) {  // every key has this digit (the top byte, when all depths share a pair of binades)
#pragma omp barrier
        continue;
      }
      for (std::size_t k = key_begin; k < key_end; ++k) to[cursor[(from[k] >> shift) & (kDigits - 1)]++] = from[k];
      std::swap(from, to);
#pragma omp barrier
    }
    if (t == 0) frame.depth_order = from;
  }
  frame.visible_count = visible;
}

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

  // The chunks hold consecutive runs of the depth order, so placing each chunk's pairs after
  // the earlier chunks' (in order within a chunk) leaves every tile's list in (depth, id) order.
  if (frame.tile_ids.size() < pairs) frame.tile_ids.resize(pairs);
  std::uint32_t* tile_ids = frame.tile_ids.data();
  ParallelErrors errors;
#pragma omp parallel for schedule(dynamic, 1) num_threads(frame.threads)
  for (int c = 0; c < chunks; ++c)
    errors.capture([&] {
      const std::vector<std::uint32_t>& tile_of = frame.chunk_tiles[c];
      const std::vector<std::uint32_t>& ids = frame.chunk_ids[c];
      std::uint32_t* cursor = frame.chunk_tile_counts[c].data();
      for (std::size_t k = 0; k < ids.size(); ++k) {
        const std::uint32_t tile = tile_of[k];
        tile_ids[tile_start[tile] + cursor[tile]++] = ids[k];
      }
    });
  errors.rethrow();

  stats.max_tile_pairs = 0;
  for (std::size_t tile = 0; tile < tiles; ++tile)
    stats.max_tile_pairs = std::max<std::uint32_t>(
        stats.max_tile_pairs, static_cast<std::uint32_t>(frame.tile_start[tile + 1] - frame.tile_start[tile]));
}

}  // namespace cpu
}  // namespace flashgs
