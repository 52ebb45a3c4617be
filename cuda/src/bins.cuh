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

}  // namespace cuda
}  // namespace flashgs
