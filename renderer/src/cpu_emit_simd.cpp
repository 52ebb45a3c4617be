// CPU emit stage, SIMD exact tile test: gm::footprint_touches_tile on a vector of a box row's
// tiles at a time (Google Highway, compiled for every x86 target, dispatched at run time).
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

std::size_t ExactBoxTiles(const gm::Footprint& f, int width, int height, int tiles_x, std::uint32_t* out) {
  const FloatTag d;
  const hn::RebindToSigned<FloatTag> di;
  const hn::RebindToUnsigned<FloatTag> du;
  const int lanes = static_cast<int>(hn::Lanes(d));
  const FloatVec w[4] = {hn::Set(d, f.whiten[0]), hn::Set(d, f.whiten[1]), hn::Set(d, f.whiten[2]),
                         hn::Set(d, f.whiten[3])};
  const FloatVec slope_x = hn::Set(d, f.edge_slope_x), threshold = hn::Set(d, f.threshold);
  const FloatVec mean_x = hn::Set(d, f.mean_x), zero = hn::Zero(d);
  const FloatVec tile_span = hn::Set(d, static_cast<float>(gm::kTileSize - 1));
  const FloatVec last_x = hn::Set(d, static_cast<float>(width - 1));
  std::size_t count = 0;
  for (int ty = f.tile_y0; ty < f.tile_y1; ++ty) {
    // The row's half of ellipse_touches_tile and whitened_ellipse_meets_rect, once per row.
    const float y0 = static_cast<float>(ty * gm::kTileSize);
    const float y1 = gm::minf(y0 + (gm::kTileSize - 1), static_cast<float>(height - 1));
    const float dy0 = y0 - f.mean_y, dy1 = y1 - f.mean_y;
    const float near_y = gm::clampf(0.0f, dy0, dy1);
    const FloatVec dy0_v = hn::Set(d, dy0), dy1_v = hn::Set(d, dy1), near_y_v = hn::Set(d, near_y);
    const FloatVec y_edge_x = hn::Set(d, f.edge_slope_y * near_y);
    const std::uint32_t row_start = static_cast<std::uint32_t>(ty) * static_cast<std::uint32_t>(tiles_x);
    for (int tx = f.tile_x0; tx < f.tile_x1; tx += lanes) {
      const FloatVec x0 = hn::ConvertTo(d, hn::Mul(hn::Iota(di, tx), hn::Set(di, gm::kTileSize)));
      const FloatVec x1 = min_as_scalar(hn::Add(x0, tile_span), last_x);
      const FloatVec dx0 = hn::Sub(x0, mean_x), dx1 = hn::Sub(x1, mean_x);
      const FloatVec near_x = clamp(zero, dx0, dx1);
      const FloatVec q_on_x_edge = whitened_q(w, near_x, clamp(hn::Mul(slope_x, near_x), dy0_v, dy1_v));
      const FloatVec q_on_y_edge = whitened_q(w, clamp(y_edge_x, dx0, dx1), near_y_v);
      const auto meets = hn::And(hn::Le(min_as_scalar(q_on_x_edge, q_on_y_edge), threshold),
                                 hn::FirstN(d, static_cast<std::size_t>(f.tile_x1 - tx)));
      const auto tiles = hn::Iota(du, row_start + static_cast<std::uint32_t>(tx));
      count += hn::CompressStore(tiles, hn::RebindMask(du, meets), du, out + count);
    }
  }
  return count;
}

// How far past the last kept tile CompressStore may write: a vector.
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
  // CompressStore writes a whole vector of the target exact_box_tiles runs on.
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
