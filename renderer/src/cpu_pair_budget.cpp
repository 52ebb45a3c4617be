// Refuses a CPU frame whose Gaussian-tile pairs cannot fit in memory before emit allocates them:
// the pairs are counted from the projected boxes, and for the exact tile test estimated from a
// sample of the boxes, so an opaque frame-filling scene costs a message, not gigabytes.
#include <algorithm>
#include <cstdio>
#include <vector>

#include "cpu_frame.h"
#include "flashgs/error.h"
#include "flashgs/frame_memory.h"

namespace flashgs {
namespace cpu {
namespace {

// Below this many bytes of pairs the boxes' count is not compared with the memory available
// (reading /proc costs more than such a frame's check is worth).
constexpr std::uint64_t kUncheckedPairBytes = std::uint64_t{256} << 20;
// Boxes the exact test is run on to estimate its share of the boxes' tiles: an even spread
// of the visible Gaussians, enough for a share within a few per cent.
constexpr std::size_t kSampledBoxes = 4096;

std::uint64_t box_tiles(const gm::Footprint& f) {
  return std::uint64_t(std::max(f.tile_x1 - f.tile_x0, 0)) * std::uint64_t(std::max(f.tile_y1 - f.tile_y0, 0));
}

// The share of the sampled boxes' tiles that the ellipses touch.
double exact_share(const Frame& frame) {
  const std::size_t n = frame.visible_count;
  const std::size_t step = std::max<std::size_t>(1, n / kSampledBoxes);
  std::uint64_t boxes = 0, touched = 0;
  std::vector<std::uint32_t> tiles;
  for (std::size_t k = 0; k < n; k += step) {
    const gm::Footprint& f = frame.footprints[static_cast<std::uint32_t>(frame.depth_order[k])];
    tiles.resize(std::max(tiles.size(), exact_box_tiles_room(f)));
    boxes += box_tiles(f);
    touched += exact_box_tiles(f, frame.camera.width, frame.camera.height, frame.camera.tiles_x, tiles.data());
  }
  return boxes ? static_cast<double>(touched) / static_cast<double>(boxes) : 1.0;
}

// Twice the boxes' tiles of an even spread of kSampledBoxes visible Gaussians, scaled to all:
// a first look that costs next to nothing, where walking every footprint in depth order cost
// pc_playbot's 1080p CPU frame about 30 ms of 500 (2-core VM under load, 2026-12-07).
std::uint64_t sampled_box_pairs(const Frame& frame) {
  const std::size_t n = frame.visible_count;
  const std::size_t step = std::max<std::size_t>(1, n / kSampledBoxes);
  std::uint64_t tiles = 0, samples = 0;
  for (std::size_t k = 0; k < n; k += step, ++samples)
    tiles += box_tiles(frame.footprints[static_cast<std::uint32_t>(frame.depth_order[k])]);
  return samples ? static_cast<std::uint64_t>(2.0 * static_cast<double>(tiles) * n / samples) : 0;
}

}  // namespace

void check_pairs_fit(const RenderOptions& options, const Frame& frame) {
  const std::uint64_t bytes_per_pair = estimate_frame_memory(BackendKind::cpu, 0, 0, 0, 1, frame.threads).pairs;
  if (sampled_box_pairs(frame) * bytes_per_pair < kUncheckedPairBytes) return;
  std::uint64_t pairs = 0;
  const std::int64_t visible = static_cast<std::int64_t>(frame.visible_count);
#pragma omp parallel for schedule(static) num_threads(frame.threads) reduction(+ : pairs)
  for (std::int64_t k = 0; k < visible; ++k)
    pairs += box_tiles(frame.footprints[static_cast<std::uint32_t>(frame.depth_order[k])]);
  if (pairs * bytes_per_pair < kUncheckedPairBytes) return;
  const AvailableMemory available = available_host_memory();
  if (available.limited_by.empty() || pairs * bytes_per_pair <= available.bytes) return;
  const bool estimated = options.uses_exact_tile_test();
  if (estimated) pairs = static_cast<std::uint64_t>(static_cast<double>(pairs) * exact_share(frame));
  if (pairs * bytes_per_pair <= available.bytes) return;
  char text[400];
  std::snprintf(text, sizeof text,
                "cpu renderer: a %dx%d frame of these %zu visible Gaussians would make %s%.3g billion "
                "Gaussian-tile pairs (%s), but %s is available (%s)",
                frame.camera.width, frame.camera.height, frame.visible_count, estimated ? "about " : "",
                static_cast<double>(pairs) / 1e9, format_bytes(pairs * bytes_per_pair).c_str(),
                format_bytes(available.bytes).c_str(), available.limited_by.c_str());
  throw Error(text);
}

}  // namespace cpu
}  // namespace flashgs
