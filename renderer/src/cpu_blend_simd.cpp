// CPU blend, SIMD kernel: the scalar kernel's rules on a vector of pixels of one tile row at a
// time (Google Highway, compiled for every x86 target and dispatched at run time).
//
// Per pixel it follows the scalar kernel, with three differences in rounding: the exponent is
// formed along the row (q = the row's smallest q plus conic_a (x - x*)^2, see the batch's
// records), the colour sums use fused multiply-adds, and alpha = opacity e^power is one exp2,
// 2^(q * -log2(e)/2 + log2 opacity), by a short polynomial (see exp2_nonpositive): relative
// error under kSimdAlphaMaxRelError (4e-6; glibc's expf and the product with opacity: about
// 1.8e-7). Such an error can move alpha across 1/255 or T across 1e-4, the same flips as
// between the CPU and CUDA backends (see test_cuda_render.cpp), so the images stay within that
// bound of the scalar kernel's (test_cpu_simd.cpp, every real scene), and as close to the fp64
// reference as the scalar kernel's (test_cpu_render.cpp). The pruning margins (0.5 in q, a
// pixel) dwarf these roundings. For a given CPU (target) and any thread count the bytes are
// the same.
#include <strings.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>

#include "cpu_frame.h"

#ifdef FLASHGS_HAVE_HWY
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "cpu_blend_simd.cpp"
#include <hwy/foreach_target.h>  // re-includes this file once per target
#include <hwy/highway.h>
#include <hwy/cache_control.h>

HWY_BEFORE_NAMESPACE();
namespace flashgs {
namespace cpu {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

constexpr int kTilePixels = gm::kTileSize * gm::kTileSize;
// A vector covers consecutive pixels of one tile row: 16 lanes (AVX-512) are a row, 8 (AVX2) half.
using FloatTag = hn::CappedTag<float, gm::kTileSize>;

// Copies what the row ranges need of the tile's Gaussians, in blend order, into arrays
// (prefetching the ones a few ahead, which lie anywhere in blend_data; the blend loop
// then finds their lines in the cache), then finds each one's rows: the scalar kernel's
// y_first / y_last, several Gaussians per vector.
void gather(const Frame& frame, const TileJob& job, int y_begin, int tile_h, TileGaussians& g) {
  const FloatTag d;
  const hn::RebindToSigned<FloatTag> di;
  const std::size_t lanes = hn::Lanes(d);
  const std::size_t count = static_cast<std::size_t>(job.count);
  const std::size_t padded = (count + lanes - 1) / lanes * lanes;
  g.grow(padded);
  constexpr std::size_t kPrefetchAhead = 16;
  for (std::size_t k = 0; k < padded; ++k) {
    if (k >= count) {  // the last vector's spare lanes: finite values, results unused
      g.mean_y[k] = g.row_q_coeff[k] = g.q_cut[k] = 0.0f;
      continue;
    }
    if (k + kPrefetchAhead < count)
      hwy::Prefetch(&frame.blend_data[job.ids[k + kPrefetchAhead]]);
    const BlendGaussian& b = frame.blend_data[job.ids[k]];
    g.mean_y[k] = b.mean_y;
    g.row_q_coeff[k] = b.row_q_coeff;
    g.q_cut[k] = b.q_cut;
  }
  const auto zero = hn::Zero(d), one = hn::Set(d, 1.0f), half = hn::Set(d, 0.5f);
  const auto top = hn::Set(d, static_cast<float>(y_begin)), last_row = hn::Set(d, static_cast<float>(tile_h - 1));
  for (std::size_t k = 0; k < padded; k += lanes) {
    const auto coeff = hn::LoadU(d, &g.row_q_coeff[k]);
    const auto q_reach = hn::Add(hn::LoadU(d, &g.q_cut[k]), half);
    const auto local_y = hn::Sub(hn::LoadU(d, &g.mean_y[k]), top);
    // As the scalar kernel: reach = sqrt((q_cut + 0.5) / coeff) + 1, or everything when coeff is 0.
    const auto reach = hn::IfThenElse(hn::Gt(coeff, zero), hn::Add(hn::Sqrt(hn::Div(q_reach, coeff)), one),
                                      hn::Set(d, 1e30f));
    auto first = hn::Max(zero, hn::Ceil(hn::Sub(local_y, reach)));
    auto last = hn::Min(last_row, hn::Floor(hn::Add(local_y, reach)));
    // q_cut + 0.5 < 0 (opacity < 1/255, drawn by the baseline): no pixel passes, no row.
    const auto none = hn::Not(hn::Ge(q_reach, zero));
    first = hn::IfThenElse(none, one, first);
    last = hn::IfThenElse(none, zero, last);
    hn::StoreU(hn::ConvertTo(di, first), di, &g.row_first[k]);
    hn::StoreU(hn::ConvertTo(di, last), di, &g.row_last[k]);
  }
}

// 2^x for x >= -32 (below, 2^-32: a lane so far out fails the alpha test as the exact value
// would). x = n + f with n = round(x), f in [-0.5, 0.5] (exact); 2^f by a degree-4 polynomial
// (minimax for the relative error, by the Remez exchange: 2.6e-6, 2.7e-6 evaluated in float
// with or without FMA; degree 5 gave 2.2e-7 for one more multiply-add per pixel, 6% of the
// blend on Zen 4, whose loop is bound by its multiply-adds); 2^n added to the
// exponent. n comes from adding 1.5 * 2^23, which rounds x to an integer in the low mantissa
// bits (so n << 23 is those bits shifted up; no float-to-int conversion). The exponent
// q * -log2(e)/2 + log2 opacity is at most 0 (q >= 0, opacity <= 1); where alpha >= 1/255
// is possible both terms lie in [-8, 0], so rounding the argument (the constant: 8 * 2^-24;
// log2 opacity: an ulp of 8; the FMA: half one) moves x by 1.25 * 2^-20 and alpha by 8.3e-7
// at most: 3.5e-6 in all, under kSimdAlphaMaxRelError (targets without FMA round once more).
// The clamp stays: without it a lane far outside a Gaussian gets a garbage alpha, possibly a
// denormal, whose arithmetic costs a microcode assist on Intel CPUs even where masked off.
template <class D, class V>
HWY_INLINE V exp2_nonpositive(D d, V x) {
  const hn::RebindToSigned<D> di;
  x = hn::Max(x, hn::Set(d, -32.0f));
  const auto round_bias = hn::Set(d, 0x1.8p23f);
  const auto biased = hn::Add(x, round_bias);  // 1.5 * 2^23 + round(x)
  const auto n = hn::Sub(biased, round_bias);
  const auto f = hn::Sub(x, n);
  auto p = hn::Set(d, 0x1.3997d6p-7f);
  p = hn::MulAdd(p, f, hn::Set(d, 0x1.ca144p-5f));
  p = hn::MulAdd(p, f, hn::Set(d, 0x1.ec06dap-3f));
  p = hn::MulAdd(p, f, hn::Set(d, 0x1.62e0dcp-1f));
  p = hn::MulAdd(p, f, hn::Set(d, 0x1.ffffe8p-1f));
  const auto exponent = hn::ShiftLeft<23>(hn::BitCast(di, biased));
  return hn::BitCast(d, hn::Add(hn::BitCast(di, p), exponent));
}

// log2(e) / 2: power * log2(e) = q * -kHalfLog2E.
constexpr float kHalfLog2E = 0.72134752044448170368f;

// The kernel's alpha before the cap, for the tests (simd_alpha).
void SimdAlpha(const float* q, const float* log2_opacity, float* alpha, std::size_t n) {
  const FloatTag d;
  const std::size_t lanes = hn::Lanes(d);
  HWY_ALIGN float q_in[gm::kTileSize], lo_in[gm::kTileSize], out[gm::kTileSize];
  for (std::size_t i = 0; i < n; i += lanes) {
    const std::size_t m = std::min(lanes, n - i);
    for (std::size_t k = 0; k < lanes; ++k) {
      q_in[k] = k < m ? q[i + k] : 0.0f;
      lo_in[k] = k < m ? log2_opacity[i + k] : 0.0f;
    }
    const auto x = hn::MulAdd(hn::Load(d, q_in), hn::Set(d, -kHalfLog2E), hn::Load(d, lo_in));
    hn::Store(exp2_nonpositive(d, x), d, out);
    for (std::size_t k = 0; k < m; ++k) alpha[i + k] = out[k];
  }
}

// std::max(a, x) and std::min(a, x) lane by lane, NaN included ((a < x) ? x : a), so that the
// spans are those of the scalar kernel for any input.
template <class V>
HWY_INLINE V max_like_std(V a, V x) {
  return hn::IfThenElse(hn::Lt(a, x), x, a);
}
template <class V>
HWY_INLINE V min_like_std(V a, V x) {
  return hn::IfThenElse(hn::Lt(x, a), x, a);
}

void BlendTileSimd(const Frame& frame, const TileJob& job, TileGaussians& g, float* rgb) {
  const FloatTag d;
  const std::size_t lanes = hn::Lanes(d);
  const int lanes_i = static_cast<int>(lanes);
  const int groups_per_row = gm::kTileSize / lanes_i;
  // One lane (HWY_SCALAR, a CPU without SIMD): 256 slots would overflow the 64-bit slot sets,
  // and a vector of one pixel has nothing over the scalar kernel, which blends instead.
  if (lanes < 4) {
    blend_tile_scalar(frame, job, rgb);
    return;
  }
  const int width = frame.camera.width, height = frame.camera.height;
  const int x_begin = job.tile_x * gm::kTileSize, y_begin = job.tile_y * gm::kTileSize;
  const int tile_w = std::min(gm::kTileSize, width - x_begin);
  const int tile_h = std::min(gm::kTileSize, height - y_begin);

  // The tile's vectors ("slots"): lane group j of row y is slot j * kTileSize + y (16 rows x at
  // most 4 groups), bit `slot` of a 64-bit set. Per slot, one vector each, next to each other
  // (one base address per slot): the pixels' column in the tile, transmittance, colour, and
  // whether they still blend (all bits set) - pixels outside the image start finished. A slot whose lanes
  // have all finished leaves live_slots (and slot_live, the same as a word per slot, which the
  // span pass reads a vector of rows at a time), and the tile stops when none is left.
  static_assert(gm::kTileSize <= 16, "64 slots: 16 rows of at most 4 lane groups");
  enum SlotField { kX, kT, kRed, kGreen, kBlue, kActive, kSlotFields };
  constexpr int kMaxSlots = 64;
  HWY_ALIGN float slot_state[kSlotFields * kTilePixels];
  const auto slot_field = [&](int slot, SlotField field) {
    return slot_state + (slot * kSlotFields + field) * lanes_i;
  };
  const hn::RebindToUnsigned<FloatTag> du;
  // Padded: a vector of rows from a Gaussian's first row may run past the last group's row 15
  // (such rows are past y_last and masked off; past other groups' row 15 they read a row of
  // the next group, masked off alike).
  HWY_ALIGN std::uint32_t slot_live[kMaxSlots + gm::kTileSize] = {};
  std::uint64_t live_slots = 0;
  const auto tile_width = hn::Set(d, static_cast<float>(tile_w));
  for (int y = 0; y < gm::kTileSize; ++y)
    for (int v = 0; v < groups_per_row; ++v) {
      const int slot = v * gm::kTileSize + y;
      const auto column = hn::Iota(d, static_cast<float>(v * lanes_i));
      const auto inside = hn::And(hn::Lt(column, tile_width), y < tile_h ? hn::FirstN(d, lanes) : hn::FirstN(d, 0));
      hn::Store(column, d, slot_field(slot, kX));
      hn::Store(hn::Set(d, 1.0f), d, slot_field(slot, kT));
      hn::Store(hn::Zero(d), d, slot_field(slot, kRed));
      hn::Store(hn::Zero(d), d, slot_field(slot, kGreen));
      hn::Store(hn::Zero(d), d, slot_field(slot, kBlue));
      hn::Store(hn::VecFromMask(d, inside), d, slot_field(slot, kActive));
      if (!hn::AllFalse(d, inside)) {
        live_slots |= std::uint64_t{1} << slot;
        slot_live[slot] = ~0u;
      }
    }

  if (job.count > 0) gather(frame, job, y_begin, tile_h, g);
  // The Gaussians blend in batches of up to kBatch that touch a live slot, slot by slot: a
  // slot's state stays in registers while the batch's Gaussians that touch it blend in order,
  // so it is loaded and stored once per batch instead of once per Gaussian. Per pixel the
  // Gaussians and the operations are those of one Gaussian at a time, in the same order.
  // Per batch member, one record: its broadcast constants (one vector each, read as memory
  // operands), then per row the two terms of its exponent (a vector of rows from y_first may
  // run past row 15). Along a row at offset dy, q is smallest at column x* = mean_x + row_slope
  // dy, where it is row_q_coeff dy^2, and grows as conic_a (x - x*)^2 (conic_a = w0^2 + w2^2):
  // so the exponent q * -log2(e)/2 + log2 opacity is a * (x - x*)^2 + c with
  // a = conic_a * -log2(e)/2 per member and c = row_q_coeff dy^2 * -log2(e)/2 + log2 opacity per
  // row, three operations per pixel instead of the whitened form's six. Both terms are <= 0, so
  // their sum does not cancel, and x - x* is taken in the tile's columns from the member's
  // centre relative to the tile (its float roundings are those of the whitened form's terms).
  // Per slot, the set of members that touch it (bit j: member j), written by the span pass a
  // vector of rows at a time. 32 members: 7.6% fewer instructions than one Gaussian at a time
  // at 1080p (callgrind, pc_playbot), 16: 4.1%.
  constexpr int kBatch = 32;
  static_assert(kBatch <= 32, "member sets of 32 bits");
  enum MemberField { kQuadratic, kMemberRed, kMemberGreen, kMemberBlue, kMemberFields };
  constexpr std::size_t kRowTerms = 2 * gm::kTileSize;
  const std::size_t centre_terms = kMemberFields * lanes, offset_terms = centre_terms + kRowTerms;
  const std::size_t member_stride = offset_terms + kRowTerms;
  HWY_ALIGN float member_records[kBatch * (kMemberFields * gm::kTileSize + 2 * kRowTerms)];
  HWY_ALIGN std::uint32_t slot_members[kMaxSlots + gm::kTileSize] = {};
  const int slot_count = groups_per_row * gm::kTileSize;
  const auto zero = hn::Zero(d), one = hn::Set(d, 1.0f), minus_half_log2e = hn::Set(d, -kHalfLog2E);
  const auto no_members = hn::Zero(du);
  const auto tile_left = hn::Set(d, static_cast<float>(x_begin));
  const auto tile_right = hn::Set(d, static_cast<float>(tile_w - 1));
  const auto alpha_max = hn::Set(d, gm::kAlphaMax), alpha_min = hn::Set(d, gm::kAlphaMin);
  const auto t_min = hn::Set(d, gm::kTransmittanceMin);
  std::uint64_t k = 0;
  while (k < job.count && live_slots != 0) {
    int members = 0;
    for (; k < job.count && members < kBatch; ++k) {
      const int y_first = g.row_first[k], y_last = g.row_last[k];
      if (y_first > y_last) continue;
      const BlendGaussian& gauss = frame.blend_data[job.ids[k]];
      const float mean_x = gauss.mean_x, mean_y = gauss.mean_y;
      float* member = member_records + static_cast<std::size_t>(members) * member_stride;
      // The slots whose row's span of pixels that can reach power_cut meets their group, and
      // which are live, get this member's bit.
      auto touches_any = no_members;
      {
        // The scalar kernel's row spans, computed the same way for a vector of rows at a time.
        const auto q_reach = hn::Set(d, gauss.q_cut + 0.5f), coeff = hn::Set(d, gauss.row_q_coeff);
        const auto slope = hn::Set(d, gauss.row_slope), inv_conic_a = hn::Set(d, gauss.inv_conic_a);
        const auto mean_y_v = hn::Set(d, mean_y), log2_opacity = hn::Set(d, gauss.log2_opacity);
        const auto centre_x = hn::Set(d, mean_x), local_centre_x = hn::Set(d, mean_x - static_cast<float>(x_begin));
        const auto member_bit = hn::Set(du, 1u << members);
        for (int row = y_first; row <= y_last; row += lanes_i) {
          const auto dy = hn::Sub(hn::Iota(d, static_cast<float>(y_begin + row)), mean_y_v);
          const auto row_q = hn::Mul(hn::Mul(coeff, dy), dy);
          const auto centre = hn::Sub(hn::Add(centre_x, hn::Mul(slope, dy)), tile_left);
          const auto half =
              hn::Add(hn::Sqrt(hn::Mul(max_like_std(zero, hn::Sub(q_reach, row_q)), inv_conic_a)), one);
          const auto first = max_like_std(zero, hn::Ceil(hn::Sub(centre, half)));
          const auto last = min_like_std(tile_right, hn::Floor(hn::Add(centre, half)));
          // The scalar kernel skips a row unless row_q <= q_reach (false for NaN) and first <=
          // last, and rows past y_last (past the tile, or outside its row range).
          const auto touched = hn::And(hn::FirstN(d, static_cast<std::size_t>(y_last + 1 - row)),
                                       hn::And(hn::Le(row_q, q_reach), hn::Le(first, last)));
          hn::StoreU(hn::Add(local_centre_x, hn::Mul(slope, dy)), d, member + centre_terms + row);
          hn::StoreU(hn::MulAdd(row_q, minus_half_log2e, log2_opacity), d, member + offset_terms + row);
          // Group j holds columns [j lanes, (j + 1) lanes): the span meets it unless it ends
          // before or starts after.
          for (int v = 0; v < groups_per_row; ++v) {
            const auto meets = hn::And(touched, hn::And(hn::Lt(first, hn::Set(d, static_cast<float>((v + 1) * lanes_i))),
                                                         hn::Ge(last, hn::Set(d, static_cast<float>(v * lanes_i)))));
            const int slot = v * gm::kTileSize + row;
            const auto touches = hn::IfThenElseZero(hn::RebindMask(du, meets), hn::LoadU(du, slot_live + slot));
            touches_any = hn::Or(touches_any, touches);
            hn::StoreU(hn::Or(hn::LoadU(du, slot_members + slot), hn::And(touches, member_bit)), du,
                       slot_members + slot);
          }
        }
      }
      if (hn::AllTrue(du, hn::Eq(touches_any, no_members))) continue;  // no live slot: not a member
      const float conic_a = gauss.whiten[0] * gauss.whiten[0] + gauss.whiten[2] * gauss.whiten[2];
      hn::Store(hn::Set(d, conic_a * -kHalfLog2E), d, member + kQuadratic * lanes);
      hn::Store(hn::Set(d, gauss.rgb[0]), d, member + kMemberRed * lanes);
      hn::Store(hn::Set(d, gauss.rgb[1]), d, member + kMemberGreen * lanes);
      hn::Store(hn::Set(d, gauss.rgb[2]), d, member + kMemberBlue * lanes);
      ++members;
    }
    // The slots some member touches.
    std::uint64_t batch_slots = 0;
    for (int slot = 0; slot < slot_count; slot += lanes_i) {
      std::uint8_t bits[(gm::kTileSize + 7) / 8] = {};
      hn::StoreMaskBits(du, hn::Not(hn::Eq(hn::Load(du, slot_members + slot), no_members)), bits);
      batch_slots |= (bits[0] | (lanes > 8 ? static_cast<std::uint64_t>(bits[1]) << 8 : 0u)) << slot;
    }
    for (; batch_slots != 0; batch_slots &= batch_slots - 1u) {
      const int slot = static_cast<int>(hwy::Num0BitsBelowLS1Bit_Nonzero64(batch_slots));
      const std::size_t row = static_cast<std::size_t>(slot % gm::kTileSize);
      float* state = slot_field(slot, kX);
      const auto x = hn::Load(d, state + kX * lanes);
      auto t = hn::Load(d, state + kT * lanes);
      auto red = hn::Load(d, state + kRed * lanes), green = hn::Load(d, state + kGreen * lanes);
      auto blue = hn::Load(d, state + kBlue * lanes);
      auto live = hn::MaskFromVec(hn::Load(d, state + kActive * lanes));
      std::uint32_t slot_batch = slot_members[slot];
      slot_members[slot] = 0;
      // No early outs per visit (no lane above power_cut, a lane finishing): the masks below
      // make those lanes no-ops, and the branches mispredicted more than the work they saved
      // (callgrind on pc_playbot, session 5: 29% fewer mispredicts for 5% more instructions).
      for (; slot_batch != 0; slot_batch &= slot_batch - 1u) {
        const std::size_t offset = hwy::Num0BitsBelowLS1Bit_Nonzero32(slot_batch) * member_stride;
        const float* constants = member_records + offset;
        const auto dx = hn::Sub(x, hn::Set(d, constants[centre_terms + row]));
        const auto exponent = hn::MulAdd(hn::Mul(dx, dx), hn::Load(d, constants + kQuadratic * lanes),
                                         hn::Set(d, constants[offset_terms + row]));
        // Only the exact test: a lane outside the row's span or below power_cut has alpha <
        // 1/255 for certain (the margins the scalar kernel's pruning relies on), so it fails
        // this test as surely as it would have been skipped there. A lane that fails it gets
        // alpha 0, which leaves its T and colour as they are, bit for bit (T - 0 T = T, colour
        // + c 0 = colour: both start at +0 or 1 and stay >= 0): no mask of its own below.
        const auto unclamped = exp2_nonpositive(d, exponent);
        const auto alpha = hn::IfThenElseZero(hn::Ge(unclamped, alpha_min), hn::Min(alpha_max, unclamped));
        // T - alpha T with one rounding: the scalar kernel's T (1 - alpha) where 1 - alpha is
        // exact (alpha >= 1/2), within an ulp elsewhere, and its product is the weight.
        const auto weight_if_blended = hn::Mul(alpha, t);
        const auto next_t = hn::NegMulAdd(alpha, t, t);
        // A live lane whose T would drop below the minimum finishes instead of blending (alpha
        // 0 never does: a live lane's T is at least the minimum); the others blend.
        const auto too_dark = hn::Lt(next_t, t_min);
        const auto blends = hn::AndNot(too_dark, live);
        live = blends;
        // Lanes that do not blend add colour * 0: the same bytes as leaving them, for one
        // select instead of three.
        const auto weight = hn::IfThenElseZero(blends, weight_if_blended);
        red = hn::MulAdd(hn::Load(d, constants + kMemberRed * lanes), weight, red);
        green = hn::MulAdd(hn::Load(d, constants + kMemberGreen * lanes), weight, green);
        blue = hn::MulAdd(hn::Load(d, constants + kMemberBlue * lanes), weight, blue);
        t = hn::IfThenElse(blends, next_t, t);
      }
      hn::Store(t, d, state + kT * lanes);
      hn::Store(red, d, state + kRed * lanes);
      hn::Store(green, d, state + kGreen * lanes);
      hn::Store(blue, d, state + kBlue * lanes);
      hn::Store(hn::VecFromMask(d, live), d, state + kActive * lanes);
      if (hn::AllFalse(d, live)) {
        live_slots &= ~(std::uint64_t{1} << slot);
        slot_live[slot] = 0;
      }
    }
  }
  // Colour plus the transmittance's share of the background, as the scalar kernel (no FMA),
  // interleaved into the image's rows; a partial lane group at the right edge pixel by pixel.
  const float* background = job.background;
  const auto bg_r = hn::Set(d, background[0]), bg_g = hn::Set(d, background[1]), bg_b = hn::Set(d, background[2]);
  for (int y = 0; y < tile_h; ++y)
    for (int v = 0; v * lanes_i < tile_w; ++v) {
      const int slot = v * gm::kTileSize + y;
      float* out = rgb + (static_cast<std::size_t>(y_begin + y) * width + x_begin + v * lanes_i) * 3;
      const auto t = hn::Load(d, slot_field(slot, kT));
      const auto out_r = hn::Add(hn::Load(d, slot_field(slot, kRed)), hn::Mul(t, bg_r));
      const auto out_g = hn::Add(hn::Load(d, slot_field(slot, kGreen)), hn::Mul(t, bg_g));
      const auto out_b = hn::Add(hn::Load(d, slot_field(slot, kBlue)), hn::Mul(t, bg_b));
      if ((v + 1) * lanes_i <= tile_w) {
        hn::StoreInterleaved3(out_r, out_g, out_b, d, out);
      } else {
        HWY_ALIGN float pixels[3 * gm::kTileSize];
        hn::StoreInterleaved3(out_r, out_g, out_b, d, pixels);
        std::copy(pixels, pixels + 3 * (tile_w - v * lanes_i), out);
      }
    }
}

const char* TargetName() { return hwy::TargetName(HWY_TARGET); }

}  // namespace HWY_NAMESPACE
}  // namespace cpu
}  // namespace flashgs
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace flashgs {
namespace cpu {

HWY_EXPORT(BlendTileSimd);
HWY_EXPORT(SimdAlpha);
HWY_EXPORT(TargetName);

void blend_tile_simd(const Frame& frame, const TileJob& tile, TileGaussians& scratch, float* rgb) {
  HWY_DYNAMIC_DISPATCH(BlendTileSimd)(frame, tile, scratch, rgb);
}

void simd_alpha(const float* q, const float* log2_opacity, float* alpha, std::size_t n) {
  HWY_DYNAMIC_DISPATCH(SimdAlpha)(q, log2_opacity, alpha, n);
}

std::string simd_target_name() { return HWY_DYNAMIC_DISPATCH(TargetName)(); }

void apply_simd_target_limit() {
  hwy::DisableTargets(0);  // what the CPU supports, whatever an earlier renderer chose
  const char* wanted = std::getenv("FLASHGS_CPU_SIMD");
  if (!wanted || !*wanted) return;
  std::int64_t chosen = 0;
  std::string names;
  for (const std::int64_t target : hwy::SupportedAndGeneratedTargets()) {
    names += std::string(names.empty() ? "" : ", ") + hwy::TargetName(target);
    if (strcasecmp(hwy::TargetName(target), wanted) == 0) chosen = target;
  }
  if (chosen == 0) {
    // Once per value: a process makes several renderers.
    static std::mutex said_mutex;
    static std::string said;
    const std::lock_guard<std::mutex> lock(said_mutex);
    if (said != wanted)
      std::fprintf(stderr, "FLASHGS_CPU_SIMD=%s: not a SIMD target this build has and this CPU runs (%s); using the best\n",
                   wanted, names.c_str());
    said = wanted;
    return;
  }
  hwy::DisableTargets(chosen - 1);  // Highway's better targets are the lower bits
}

}  // namespace cpu
}  // namespace flashgs
#endif  // HWY_ONCE

#else  // no Highway: the scalar kernel

namespace flashgs {
namespace cpu {

void blend_tile_simd(const Frame& frame, const TileJob& tile, TileGaussians&, float* rgb) {
  blend_tile_scalar(frame, tile, rgb);
}

void simd_alpha(const float* q, const float* log2_opacity, float* alpha, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) alpha[i] = std::exp2(log2_opacity[i]) * std::exp(-0.5f * q[i]);
}

std::string simd_target_name() { return "scalar"; }

void apply_simd_target_limit() {
  const char* wanted = std::getenv("FLASHGS_CPU_SIMD");
  if (wanted && *wanted)
    std::fprintf(stderr, "FLASHGS_CPU_SIMD=%s: this build has no SIMD kernels (built without Highway)\n", wanted);
}

}  // namespace cpu
}  // namespace flashgs
#endif
