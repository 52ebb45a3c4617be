// CPU emit stage: one key per Gaussian-tile pair (baseline: every tile of the box; flash with
// the exact test: only tiles the ellipse touches).
#include <algorithm>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "cpu_frame.h"
#include "parallel_errors.h"

namespace flashgs {
namespace cpu {

void emit(const Scene& scene, const RenderOptions& options, Frame& frame, FrameStats& stats) {
  const std::int64_t n = static_cast<std::int64_t>(scene.size());
  const std::size_t tiles = static_cast<std::size_t>(frame.camera.tiles_x) * frame.camera.tiles_y;
  const bool exact = options.uses_exact_tile_test();
  const int width = frame.camera.width, height = frame.camera.height, tiles_x = frame.camera.tiles_x;
  std::uint64_t visible = 0, ellipse_missed = 0;

  // Static contiguous chunks: thread t of a team of T owns Gaussians [t n / T, (t + 1) n / T),
  // so the pair lists, concatenated in thread order, are in Gaussian order whatever the timing.
  // T is the team OpenMP grants, which may be smaller than frame.threads (OMP_THREAD_LIMIT,
  // OMP_DYNAMIC, a render called inside another parallel region).
  ParallelErrors errors;
#pragma omp parallel num_threads(frame.threads) reduction(+ : visible, ellipse_missed)
  {
#ifdef _OPENMP
    const int t = omp_get_thread_num(), team = omp_get_num_threads();
#else
    const int t = 0, team = 1;
#endif
#pragma omp single
    errors.capture([&] {
      frame.emit_chunks = team;
      // Grown only: shrinking would free the inner vectors' capacity.
      if (frame.thread_tiles.size() < static_cast<std::size_t>(team)) {
        frame.thread_tiles.resize(team);
        frame.thread_keys.resize(team);
        frame.thread_tile_counts.resize(team);
      }
    });
    errors.capture([&] {
      // The outputs as this thread's locals (swapped in and back, capacity kept): the vectors'
      // headers sit side by side in frame, and a push_back to one would invalidate the cache
      // line of the others' (false sharing cost more than the work at 2 threads).
      std::vector<std::uint32_t> out_tiles, counts;
      std::vector<std::uint64_t> out_keys;
      out_tiles.swap(frame.thread_tiles[t]);
      out_keys.swap(frame.thread_keys[t]);
      counts.swap(frame.thread_tile_counts[t]);
      out_tiles.clear();
      out_keys.clear();
      counts.assign(tiles, 0);
      std::uint64_t my_visible = 0, my_missed = 0;
      const gm::Footprint* footprints = frame.footprints.data();
      std::uint8_t* cull = frame.cull.data();
      const std::int64_t begin = n * t / team, end = n * (t + 1) / team;
      for (std::int64_t i = begin; i < end; ++i) {
        if (cull[i] != gm::kVisible) continue;
        const gm::Footprint& f = footprints[i];
        const std::uint64_t key_low =
            (static_cast<std::uint64_t>(gm::depth_bits(f.depth)) << 32) | static_cast<std::uint64_t>(i);
        const std::size_t emitted_before = out_keys.size();
        for (int ty = f.tile_y0; ty < f.tile_y1; ++ty)
          for (int tx = f.tile_x0; tx < f.tile_x1; ++tx) {
            if (exact && !gm::footprint_touches_tile(f, tx, ty, width, height)) continue;
            const std::uint32_t tile = static_cast<std::uint32_t>(ty) * tiles_x + tx;
            out_tiles.push_back(tile);
            out_keys.push_back(key_low);
            counts[tile]++;
          }
        if (out_keys.size() > emitted_before) {
          my_visible++;
        } else {  // the box reached the image, the ellipse did not
          cull[i] = gm::kCulledOffscreen;
          my_missed++;
        }
      }
      visible += my_visible;
      ellipse_missed += my_missed;
      out_tiles.swap(frame.thread_tiles[t]);
      out_keys.swap(frame.thread_keys[t]);
      counts.swap(frame.thread_tile_counts[t]);
    });
  }
  errors.rethrow();
  stats.visible = visible;
  std::uint64_t pairs = 0;
  for (int t = 0; t < frame.emit_chunks; ++t) pairs += frame.thread_keys[t].size();
  stats.kv_pairs = pairs;
  stats.culled_offscreen += ellipse_missed;  // project counted the boxes that missed the image
}

}  // namespace cpu
}  // namespace flashgs
