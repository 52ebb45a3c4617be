// CPU blend stage: schedules the tiles (densest first) over the threads and runs a kernel on each.
#include <algorithm>
#include <atomic>

#include "cpu_frame.h"
#include "parallel_errors.h"

namespace flashgs {
namespace cpu {
namespace {

// Tiles by the bit length of their pair count, longest first (by index within a class), so
// the long tiles start at once and the short ones fill in at the end instead of one core
// finishing a dense tile alone. A counting sort: a comparison sort of the tiles took 0.7 ms
// at 1080p and 3.6 ms at 4K on one core, while the blend of a 4K frame on 16 cores is ~60 ms.
void order_tiles_by_pairs(Frame& frame, std::size_t tiles) {
  constexpr int kClasses = 65;  // bit lengths 0 (an empty tile) .. 64
  std::size_t class_start[kClasses + 1] = {};
  const std::uint64_t* start = frame.tile_start.data();
  auto class_of = [start](std::size_t tile) {
    std::uint64_t pairs = start[tile + 1] - start[tile];
    int bits = 0;
    for (; pairs; pairs >>= 1) ++bits;
    return kClasses - 1 - bits;  // the longest class first
  };
  for (std::size_t tile = 0; tile < tiles; ++tile) class_start[class_of(tile) + 1]++;
  for (int c = 0; c < kClasses; ++c) class_start[c + 1] += class_start[c];
  frame.tile_order.resize(tiles);
  for (std::size_t tile = 0; tile < tiles; ++tile)
    frame.tile_order[class_start[class_of(tile)]++] = static_cast<std::uint32_t>(tile);
}

}  // namespace

bool blend(const RenderOptions& options, Frame& frame, BlendKernel kernel, const std::function<bool()>& cancelled,
           float* rgb, const PixelPlanes* planes) {
  const int tiles_x = frame.camera.tiles_x;
  const std::size_t tiles = static_cast<std::size_t>(tiles_x) * frame.camera.tiles_y;
  order_tiles_by_pairs(frame, tiles);

  std::atomic<bool> stop{false};
  ParallelErrors errors;
  const std::int64_t count = static_cast<std::int64_t>(tiles);
#pragma omp parallel for schedule(dynamic, 1) num_threads(frame.threads)
  for (std::int64_t i = 0; i < count; ++i)
    errors.capture([&] {
      if (stop.load(std::memory_order_relaxed)) return;
      if (cancelled && cancelled()) {
        stop.store(true, std::memory_order_relaxed);
        return;
      }
      const std::uint32_t tile = frame.tile_order[i];
      const std::uint64_t begin = frame.tile_start[tile], end = frame.tile_start[tile + 1];
      const TileJob job{frame.tile_ids.data() + begin, end - begin, static_cast<int>(tile % tiles_x),
                        static_cast<int>(tile / tiles_x), options.background};
      if (kernel == BlendKernel::scalar || planes)
        blend_tile_scalar(frame, job, rgb, planes);
      else
        blend_tile_simd(frame, job, rgb, kernel == BlendKernel::simd ? SpanPruning::on : SpanPruning::off);
    });
  errors.rethrow();
  return !stop.load();
}

}  // namespace cpu
}  // namespace flashgs
