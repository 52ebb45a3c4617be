// CPU emit stage: a (tile, Gaussian id) pair per tile a visible Gaussian reaches (baseline: every
// tile of the box; flash with the exact test: only tiles the ellipse touches), in depth order.
#include <algorithm>

#include "cpu_frame.h"
#include "parallel_errors.h"

namespace flashgs {
namespace cpu {
namespace {

// Footprints are read in depth order, anywhere in the array: this many Gaussians ahead are
// prefetched.
constexpr std::int64_t kPrefetchAhead = 16;
// Boxes of at least this many tiles take the vector test (exact_box_tiles), smaller ones the
// scalar test: a call per box and a vector's latency chain cost more than a few scalar tests
// (pc_playbot 1080p, 2 threads of a Zen 4 VM: emit 13.1 ms with the vector test for boxes 4+
// tiles wide, 9.5-9.9 for boxes of 8+ tiles, 9.4-9.6 from 5, 10.4 from 3; batching several
// boxes' tiles into shared vectors, gathered by lane, 11.2-11.9).
constexpr int kVectorBoxTiles = 8;

}  // namespace

void emit(const RenderOptions& options, Frame& frame, FrameStats& stats) {
  const std::int64_t n = static_cast<std::int64_t>(frame.visible_count);
  const std::size_t tiles = static_cast<std::size_t>(frame.camera.tiles_x) * frame.camera.tiles_y;
  const bool exact = options.uses_exact_tile_test();
  const int width = frame.camera.width, height = frame.camera.height, tiles_x = frame.camera.tiles_x;
  std::uint64_t visible = 0, ellipse_missed = 0;

  // Chunk c holds entries [c n / C, (c + 1) n / C) of the depth order: the pair lists,
  // concatenated in chunk order, are in (depth, id) order however the chunks were scheduled
  // (sort_by_tile relies on it).
  const int chunks = emit_chunk_count(frame.threads, static_cast<std::uint64_t>(n));
  frame.emit_chunks = chunks;
  // Grown only: shrinking would free the inner vectors' capacity.
  if (frame.chunk_tiles.size() < static_cast<std::size_t>(chunks)) {
    frame.chunk_tiles.resize(chunks);
    frame.chunk_ids.resize(chunks);
    frame.chunk_tile_counts.resize(chunks);
  }
  ParallelErrors errors;
#pragma omp parallel for schedule(dynamic, 1) num_threads(frame.threads) reduction(+ : visible, ellipse_missed)
  for (int c = 0; c < chunks; ++c)
    errors.capture([&] {
      // The outputs as this thread's locals (swapped in and back, capacity kept): the vectors'
      // headers sit side by side in frame, and a push_back to one would invalidate the cache
      // line of the others' (false sharing cost more than the work at 2 threads).
      std::vector<std::uint32_t> out_tiles, out_ids, counts, box_tiles;
      out_tiles.swap(frame.chunk_tiles[c]);
      out_ids.swap(frame.chunk_ids[c]);
      counts.swap(frame.chunk_tile_counts[c]);
      out_tiles.clear();
      out_ids.clear();
      counts.assign(tiles, 0);
      std::uint64_t my_visible = 0, my_missed = 0;
      const gm::Footprint* footprints = frame.footprints.data();
      std::uint8_t* cull = frame.cull.data();
      const std::uint64_t* order = frame.depth_order;
      const std::int64_t begin = n * c / chunks, end = n * (c + 1) / chunks;
      for (std::int64_t k = begin; k < end; ++k) {
        if (k + kPrefetchAhead < end) {  // both cache lines a footprint may straddle
          const std::uint32_t later = static_cast<std::uint32_t>(order[k + kPrefetchAhead]);
          const char* ahead = reinterpret_cast<const char*>(&footprints[later]);
          __builtin_prefetch(ahead);
          __builtin_prefetch(ahead + sizeof(gm::Footprint) - 1);
        }
        const std::uint32_t i = static_cast<std::uint32_t>(order[k]);
        const gm::Footprint& f = footprints[i];
        const std::size_t emitted_before = out_ids.size();
        if (exact && (f.tile_x1 - f.tile_x0) * (f.tile_y1 - f.tile_y0) >= kVectorBoxTiles) {
          const std::size_t room = exact_box_tiles_room(f);
          if (box_tiles.size() < room) box_tiles.resize(room);
          const std::size_t touched = exact_box_tiles(f, width, height, tiles_x, box_tiles.data());
          out_tiles.insert(out_tiles.end(), box_tiles.begin(), box_tiles.begin() + touched);
          out_ids.insert(out_ids.end(), touched, i);
          for (std::size_t b = 0; b < touched; ++b) counts[box_tiles[b]]++;
        } else {
          for (int ty = f.tile_y0; ty < f.tile_y1; ++ty)
            for (int tx = f.tile_x0; tx < f.tile_x1; ++tx) {
              if (exact && !gm::footprint_touches_tile(f, tx, ty, width, height)) continue;
              const std::uint32_t tile = static_cast<std::uint32_t>(ty) * tiles_x + tx;
              out_tiles.push_back(tile);
              out_ids.push_back(i);
              counts[tile]++;
            }
        }
        if (out_ids.size() > emitted_before) {
          my_visible++;
        } else {  // the box reached the image, the ellipse did not
          cull[i] = gm::kCulledOffscreen;
          my_missed++;
        }
      }
      visible += my_visible;
      ellipse_missed += my_missed;
      out_tiles.swap(frame.chunk_tiles[c]);
      out_ids.swap(frame.chunk_ids[c]);
      counts.swap(frame.chunk_tile_counts[c]);
    });
  errors.rethrow();
  stats.visible = visible;
  std::uint64_t pairs = 0;
  for (int c = 0; c < chunks; ++c) pairs += frame.chunk_ids[c].size();
  stats.kv_pairs = pairs;
  stats.sorted_pairs = pairs;
  stats.culled_offscreen += ellipse_missed;  // project counted the boxes that missed the image
}

}  // namespace cpu
}  // namespace flashgs
