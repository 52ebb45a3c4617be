// Device side of the sort bins (BinGrid): a Gaussian's box in bins, the tiles of one bin it
// touches, and the pair value that carries them.
#pragma once

#include "device_common.cuh"
#include "flashgs/gaussian_math.h"
#include "pipeline.h"

namespace flashgs {
namespace cuda {

// Bins [x0, x1) x [y0, y1) holding a footprint's tile box (which is never empty here).
struct BinBox {
  int x0, y0, x1, y1;
  __device__ BinBox(const gm::Footprint& f, int shift)
      : x0(f.tile_x0 >> shift), y0(f.tile_y0 >> shift), x1(((f.tile_x1 - 1) >> shift) + 1),
        y1(((f.tile_y1 - 1) >> shift) + 1) {}
  __device__ int width() const { return x1 - x0; }
  __device__ unsigned count() const { return static_cast<unsigned>(x1 - x0) * static_cast<unsigned>(y1 - y0); }
};

// The tiles of bin (bx, by) that lie in the tile box [tx0, tx1) x [ty0, ty1) and pass
// `touches(tx, ty)`, as bits row-major in the bin: the same tiles, tested the same way, as
// the per-tile emission keys, so the pair set is the same at any bin size.
template <typename TOUCHES>
__device__ __forceinline__ unsigned bin_tiles(int shift, int bx, int by, int tx0, int ty0, int tx1, int ty1,
                                              TOUCHES touches) {
  static_assert(kMacroBinShift == 1, "bins are a tile or 2x2 tiles");
  if (shift == 0) return touches(bx, by) ? 1u : 0u;  // a bin of the box is a tile of the box
  // Every tile is tested, in the box or not (a tile beyond the image's edge is a valid, if
  // empty, rectangle), and the box applied after: lanes of a warp test different bins, so a
  // test skipped by one lane was run for another anyway, and without branches there is no
  // divergence to reconverge.
  unsigned bits = 0;
#pragma unroll
  for (int k = 0; k < 4; ++k) {
    const int tx = 2 * bx + (k & 1), ty = 2 * by + (k >> 1);
    const bool in_box = tx >= tx0 && tx < tx1 && ty >= ty0 && ty < ty1;
    const bool touched = touches(tx, ty);
    bits |= static_cast<unsigned>(in_box & touched) << k;
  }
  return bits;
}

// bin_tiles for a whole footprint (the exact test, or every tile of the box when !exact).
__device__ __forceinline__ unsigned footprint_bin_tiles(const gm::Footprint& f, int shift, int bx, int by,
                                                        const gm::CameraParams& cam, bool exact) {
  return bin_tiles(shift, bx, by, f.tile_x0, f.tile_y0, f.tile_x1, f.tile_y1, [&](int tx, int ty) {
    return !exact || gm::footprint_touches_tile(f, tx, ty, cam.width, cam.height);
  });
}

// A pair's value: its blend record, and with bins larger than a tile the bits of the bin's
// tiles that it touches above it.
__device__ __forceinline__ std::uint32_t pair_value(const BinGrid& bins, unsigned record, unsigned tile_bits) {
  return bins.shift == 0 ? record : record | (tile_bits << kBinTileBitsShift);
}

// Where one bin's four tile lists go (FrameBuffers::tile_lists; tile q row-major in the bin).
struct BinLists {
  std::uint32_t* top;
  std::uint32_t* bottom;
  unsigned start, length;  // the bin's range in the sorted values
  __device__ unsigned list_start(int q) const { return 2 * start + (q & 1) * length; }
  __device__ std::uint32_t* list(int q) const { return (q < 2 ? top : bottom) + list_start(q); }
};

// Whether a binned pair value carries tile q of its bin.
__device__ __forceinline__ bool carries(std::uint32_t value, int q) { return (value >> (kBinTileBitsShift + q)) & 1u; }

// Counts a loaded run's values (those before `end`) per tile. Groups of 32 past the end are
// skipped, a whole warp at once: a bin's share is often a few groups of the run.
__device__ __forceinline__ void count_run_tiles(const std::uint32_t (&v)[kWarpLoads], unsigned first, unsigned end,
                                                unsigned (&count)[4]) {
#pragma unroll
  for (int k = 0; k < kWarpLoads; ++k) {
    if (first + k * kWarp >= end) break;
#pragma unroll
    for (int q = 0; q < 4; ++q) count[q] += __popc(__ballot_sync(kFullMask, carries(v[k], q)));
  }
}

// Appends a loaded run's records (values before `end`) to the tile lists in order: tile q's
// next at place next[q].
__device__ __forceinline__ void place_run_tiles(const BinLists& lists, const std::uint32_t (&v)[kWarpLoads],
                                                unsigned first, unsigned end, unsigned (&next)[4]) {
  const unsigned lanes_below = (1u << lane_id()) - 1u;
#pragma unroll
  for (int k = 0; k < kWarpLoads; ++k) {
    if (first + k * kWarp >= end) break;
#pragma unroll
    for (int q = 0; q < 4; ++q) {
      const bool mine = carries(v[k], q);
      const unsigned ballot = __ballot_sync(kFullMask, mine);
      if (mine) lists.list(q)[next[q] + __popc(ballot & lanes_below)] = v[k] & kRecordMask;
      next[q] += __popc(ballot);
    }
  }
}

// Writes a bin's values (`values`, lists.length of them, in bin order) into its four tile
// lists in that order, tile q getting the records of the values that carry it, and returns the
// lists' lengths in `total`. WARPS warps take consecutive shares (with WARPS > 1, all threads
// of the block, whose warps they must be, call): a first pass counts each share's values per
// tile into `warp_counts` (shared memory), so that the second knows where its values go.
template <int WARPS>
__device__ void write_bin_lists(const std::uint32_t* values, const BinLists& lists, unsigned (*warp_counts)[4],
                                unsigned (&total)[4]) {
  const unsigned warp = WARPS == 1 ? 0u : threadIdx.x / kWarp;
  const WarpShare share(lists.length, WARPS, warp);
  unsigned next[4] = {0, 0, 0, 0};
  if constexpr (WARPS > 1) {
    unsigned count[4] = {0, 0, 0, 0};
    for (unsigned first = share.lo; first < share.hi; first += kWarpRun) {  // warp-uniform
      std::uint32_t v[kWarpLoads];
      load_run(values, first, share.hi, v);
      count_run_tiles(v, first, share.hi, count);
    }
    if (lane_id() == 0)
#pragma unroll
      for (int q = 0; q < 4; ++q) warp_counts[warp][q] = count[q];
    __syncthreads();
#pragma unroll
    for (int q = 0; q < 4; ++q) {
      total[q] = 0;
      for (unsigned w = 0; w < WARPS; ++w) {
        if (w == warp) next[q] = total[q];
        total[q] += warp_counts[w][q];
      }
    }
  }
  for (unsigned first = share.lo; first < share.hi; first += kWarpRun) {  // warp-uniform
    std::uint32_t v[kWarpLoads];
    load_run(values, first, share.hi, v);
    place_run_tiles(lists, v, first, share.hi, next);
  }
  if constexpr (WARPS == 1)
#pragma unroll
    for (int q = 0; q < 4; ++q) total[q] = next[q];
}

// Thread q < 4 records tile q's list of `bin`, `placed[q]` records long (tiles beyond the
// image's edge have none).
__device__ __forceinline__ void record_tile_list(const BinGrid& bins, int tiles_x, int tiles_y, uint2* tile_lists,
                                                 unsigned bin, const BinLists& lists, const unsigned (&placed)[4],
                                                 unsigned q) {
  if (q >= 4) return;
  const int tx = static_cast<int>(bin % static_cast<unsigned>(bins.x)) * 2 + static_cast<int>(q & 1u);
  const int ty = static_cast<int>(bin / static_cast<unsigned>(bins.x)) * 2 + static_cast<int>(q >> 1);
  if (tx >= tiles_x || ty >= tiles_y) return;
  const unsigned count = q == 0 ? placed[0] : q == 1 ? placed[1] : q == 2 ? placed[2] : placed[3];
  const unsigned start = lists.list_start(static_cast<int>(q));
  tile_lists[static_cast<std::uint64_t>(ty) * static_cast<unsigned>(tiles_x) + static_cast<unsigned>(tx)] =
      make_uint2(start, start + count);
}

}  // namespace cuda
}  // namespace flashgs
