// Device side of the sort bins (BinGrid): a Gaussian's box in bins, the tiles of one bin it
// touches, and the pair value that carries them.
#pragma once

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
  unsigned bits = 0;
#pragma unroll
  for (int k = 0; k < 4; ++k) {
    const int tx = 2 * bx + (k & 1), ty = 2 * by + (k >> 1);
    if (tx >= tx0 && tx < tx1 && ty >= ty0 && ty < ty1 && touches(tx, ty)) bits |= 1u << k;
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
