// CPU emit stage, SIMD exact tile test: gm::footprint_touches_tile on a vector of a box's tiles
// at a time, a row's or, in a box narrower than a vector, several rows' (Google Highway,
// compiled for every x86 target, dispatched at run time).
//
// The decisions are the scalar test's, bit for bit (tests/test_cpu_simd.cpp): each operation is
// the scalar code's in its order, a Mul then an Add, never a MulAdd (this file is compiled with
// -ffp-contract=off like the rest of the library), and min / clamp as the scalar ternaries.
#include <cstdint>

#include "cpu_frame.h"

#ifdef FLASHGS_HAVE_HWY
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "cpu_emit_simd.cpp"
#include <hwy/foreach_target.h>  // re-includes this file once per target
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace flashgs {
namespace cpu {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using FloatTag = hn::ScalableTag<float>;
using FloatVec = hn::Vec<FloatTag>;

// gm::clampf and gm::minf: the same operand wins on ties and NaN as in the ternaries.
HWY_INLINE FloatVec clamp(FloatVec v, FloatVec lo, FloatVec hi) {
  return hn::IfThenElse(hn::Lt(v, lo), lo, hn::IfThenElse(hn::Gt(v, hi), hi, v));
}
HWY_INLINE FloatVec min_as_scalar(FloatVec a, FloatVec b) { return hn::IfThenElse(hn::Lt(a, b), a, b); }

// gm::whitened_q per lane.
HWY_INLINE FloatVec whitened_q(const FloatVec (&w)[4], FloatVec dx, FloatVec dy) {
  const FloatVec u = hn::Add(hn::Mul(w[0], dx), hn::Mul(w[1], dy));
  const FloatVec v = hn::Add(hn::Mul(w[2], dx), hn::Mul(w[3], dy));
  return hn::Add(hn::Mul(u, u), hn::Mul(v, v));
}

// The test for a vector of tiles (tile_x, tile_y), as gm::ellipse_touches_tile per lane.
struct FootprintVectors {
  FloatVec w[4], slope_x, slope_y, threshold, mean_x, mean_y, last_x, last_y;
};

HWY_INLINE hn::Mask<FloatTag> touches_tiles(const FootprintVectors& f, hn::Vec<hn::RebindToSigned<FloatTag>> tile_x,
                                            hn::Vec<hn::RebindToSigned<FloatTag>> tile_y) {
  const FloatTag d;
  const hn::RebindToSigned<FloatTag> di;
  const FloatVec zero = hn::Zero(d), tile_span = hn::Set(d, static_cast<float>(gm::kTileSize - 1));
  const FloatVec x0 = hn::ConvertTo(d, hn::Mul(tile_x, hn::Set(di, gm::kTileSize)));
  const FloatVec y0 = hn::ConvertTo(d, hn::Mul(tile_y, hn::Set(di, gm::kTileSize)));
  const FloatVec x1 = min_as_scalar(hn::Add(x0, tile_span), f.last_x);
  const FloatVec y1 = min_as_scalar(hn::Add(y0, tile_span), f.last_y);
  const FloatVec dx0 = hn::Sub(x0, f.mean_x), dx1 = hn::Sub(x1, f.mean_x);
  const FloatVec dy0 = hn::Sub(y0, f.mean_y), dy1 = hn::Sub(y1, f.mean_y);
  const FloatVec near_x = clamp(zero, dx0, dx1), near_y = clamp(zero, dy0, dy1);
  const FloatVec q_on_x_edge = whitened_q(f.w, near_x, clamp(hn::Mul(f.slope_x, near_x), dy0, dy1));
  const FloatVec q_on_y_edge = whitened_q(f.w, clamp(hn::Mul(f.slope_y, near_y), dx0, dx1), near_y);
  return hn::Le(min_as_scalar(q_on_x_edge, q_on_y_edge), f.threshold);
}

std::size_t ExactBoxTiles(const gm::Footprint& f, int width, int height, int tiles_x, std::uint32_t* out) {
  const FloatTag d;
  const hn::RebindToSigned<FloatTag> di;
  const hn::RebindToUnsigned<FloatTag> du;
  const int lanes = static_cast<int>(hn::Lanes(d));
  const FootprintVectors fv{{hn::Set(d, f.whiten[0]), hn::Set(d, f.whiten[1]), hn::Set(d, f.whiten[2]),
                             hn::Set(d, f.whiten[3])},
                            hn::Set(d, f.edge_slope_x),
                            hn::Set(d, f.edge_slope_y),
                            hn::Set(d, f.threshold),
                            hn::Set(d, f.mean_x),
                            hn::Set(d, f.mean_y),
                            hn::Set(d, static_cast<float>(width - 1)),
                            hn::Set(d, static_cast<float>(height - 1))};
  const auto tiles_x_v = hn::Set(di, tiles_x);
  std::size_t count = 0;
  const auto keep = [&](hn::Vec<decltype(di)> tx, hn::Vec<decltype(di)> ty, int valid) {
    const auto meets = hn::And(touches_tiles(fv, tx, ty), hn::FirstN(d, static_cast<std::size_t>(valid)));
    const auto tiles = hn::BitCast(du, hn::Add(hn::Mul(ty, tiles_x_v), tx));
    // Compressed in a register and stored whole: CompressStore's form that writes memory is
    // microcoded on AMD Zen 4 (pc_playbot 1080p emit 10.5-11.2 -> 9.5-9.6 ms there, 2 threads).
    const auto kept = hn::RebindMask(du, meets);
    hn::StoreU(hn::Compress(tiles, kept), du, out + count);
    count += hn::CountTrue(du, kept);
  };
  const int box_w = f.tile_x1 - f.tile_x0, box_h = f.tile_y1 - f.tile_y0;
  if (box_w >= lanes) {  // a vector of a row's tiles at a time
    for (int ty = f.tile_y0; ty < f.tile_y1; ++ty)
      for (int tx = f.tile_x0; tx < f.tile_x1; tx += lanes) keep(hn::Iota(di, tx), hn::Set(di, ty), f.tile_x1 - tx);
    return count;
  }
  // A narrow box: a vector of its tiles in row-major order, across rows. Tile k of the box is
  // at row k / box_w, found as floor((k + 0.5) / box_w) in float: k + 0.5 lies at least 0.5 from
  // a multiple of box_w, and the two roundings move the quotient by less than k 2^-23 / box_w,
  // below that margin for k < 2^22 (the box has at most 15 x 4096 tiles).
  const int area = box_w * box_h;
  const FloatVec inv_w = hn::Set(d, 1.0f / static_cast<float>(box_w)), half = hn::Set(d, 0.5f);
  const auto box_w_v = hn::Set(di, box_w), x0 = hn::Set(di, f.tile_x0), y0 = hn::Set(di, f.tile_y0);
  for (int k = 0; k < area; k += lanes) {
    const auto index = hn::Iota(di, k);
    const auto row = hn::ConvertTo(di, hn::Floor(hn::Mul(hn::Add(hn::ConvertTo(d, index), half), inv_w)));
    const auto column = hn::Sub(index, hn::Mul(row, box_w_v));
    keep(hn::Add(x0, column), hn::Add(y0, row), area - k);
  }
  return count;
}

// How far past the last kept tile a stored vector reaches: a vector.
std::size_t VectorLanes() { return hn::Lanes(FloatTag()); }

}  // namespace HWY_NAMESPACE
}  // namespace cpu
}  // namespace flashgs
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace flashgs {
namespace cpu {

HWY_EXPORT(ExactBoxTiles);
HWY_EXPORT(VectorLanes);

std::size_t exact_box_tiles(const gm::Footprint& f, int width, int height, int tiles_x, std::uint32_t* out) {
  return HWY_DYNAMIC_DISPATCH(ExactBoxTiles)(f, width, height, tiles_x, out);
}

std::size_t exact_box_tiles_room(const gm::Footprint& f) {
  // Each row's or rows' kept tiles are stored as a whole vector of the target in use.
  return static_cast<std::size_t>(f.tile_x1 - f.tile_x0) * static_cast<std::size_t>(f.tile_y1 - f.tile_y0) +
         HWY_DYNAMIC_DISPATCH(VectorLanes)();
}

}  // namespace cpu
}  // namespace flashgs
#endif  // HWY_ONCE

#else  // no Highway: the scalar test

namespace flashgs {
namespace cpu {

std::size_t exact_box_tiles(const gm::Footprint& f, int width, int height, int tiles_x, std::uint32_t* out) {
  std::size_t count = 0;
  for (int ty = f.tile_y0; ty < f.tile_y1; ++ty)
    for (int tx = f.tile_x0; tx < f.tile_x1; ++tx)
      if (gm::footprint_touches_tile(f, tx, ty, width, height))
        out[count++] = static_cast<std::uint32_t>(ty) * static_cast<std::uint32_t>(tiles_x) + static_cast<std::uint32_t>(tx);
  return count;
}

std::size_t exact_box_tiles_room(const gm::Footprint& f) {
  return static_cast<std::size_t>(f.tile_x1 - f.tile_x0) * static_cast<std::size_t>(f.tile_y1 - f.tile_y0);
}

}  // namespace cpu
}  // namespace flashgs
#endif
