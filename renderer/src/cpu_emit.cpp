// CPU emit stage: one key per Gaussian-tile pair (baseline: every tile of the box; flash with
// the exact test: only tiles the ellipse touches).
#include <algorithm>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "cpu_frame.h"

namespace flashgs {
namespace cpu {

void emit(const Scene& scene, const RenderOptions& options, Frame& frame, FrameStats& stats) {
  const std::int64_t n = static_cast<std::int64_t>(scene.size());
  const int threads = frame.threads;
  const std::size_t tiles = static_cast<std::size_t>(frame.camera.tiles_x) * frame.camera.tiles_y;
  frame.thread_tiles.resize(threads);
  frame.thread_keys.resize(threads);
  frame.thread_tile_counts.resize(threads);
  const bool exact = options.uses_exact_tile_test();
  const int width = frame.camera.width, height = frame.camera.height, tiles_x = frame.camera.tiles_x;
  std::uint64_t visible = 0, ellipse_missed = 0;

  // Static contiguous chunks: thread t owns Gaussians [t n / T, (t + 1) n / T), so the pair
  // lists, concatenated in thread order, are in Gaussian order whatever the timing.
#pragma omp parallel num_threads(threads) reduction(+ : visible, ellipse_missed)
  {
#ifdef _OPENMP
    const int t = omp_get_thread_num();
#else
    const int t = 0;
#endif
    std::vector<std::uint32_t>& out_tiles = frame.thread_tiles[t];
    std::vector<std::uint64_t>& out_keys = frame.thread_keys[t];
    std::vector<std::uint32_t>& counts = frame.thread_tile_counts[t];
    out_tiles.clear();
    out_keys.clear();
    counts.assign(tiles, 0);
    const std::int64_t begin = n * t / threads, end = n * (t + 1) / threads;
    for (std::int64_t i = begin; i < end; ++i) {
      if (frame.cull[i] != gm::kVisible) continue;
      const gm::Footprint& f = frame.footprints[i];
      const std::uint64_t key_low =
          (static_cast<std::uint64_t>(gm::depth_bits(f.depth)) << 32) | static_cast<std::uint64_t>(i);
      bool any = false;
      for (int ty = f.tile_y0; ty < f.tile_y1; ++ty)
        for (int tx = f.tile_x0; tx < f.tile_x1; ++tx) {
          if (exact && !gm::footprint_touches_tile(f, tx, ty, width, height)) continue;
          const std::uint32_t tile = static_cast<std::uint32_t>(ty) * tiles_x + tx;
          out_tiles.push_back(tile);
          out_keys.push_back(key_low);
          counts[tile]++;
          any = true;
        }
      if (any) {
        visible++;
      } else {  // the box reached the image, the ellipse did not
        frame.cull[i] = gm::kCulledOffscreen;
        ellipse_missed++;
      }
    }
  }
  stats.visible = visible;
  std::uint64_t pairs = 0;
  for (int t = 0; t < threads; ++t) pairs += frame.thread_keys[t].size();
  stats.kv_pairs = pairs;
  stats.culled_offscreen += ellipse_missed;  // project counted the boxes that missed the image
}

}  // namespace cpu
}  // namespace flashgs
