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
// reference as the scalar kernel's (test_cpu_render.cpp). The row spans' margins (kSpanQMargin
// and beside it) exceed these roundings more than 30x, so pruning changes no byte
// (test_cpu_simd.cpp). For a given CPU (target) and any thread count the bytes are the same.
#include <strings.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
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

#if HWY_TARGET == HWY_SCALAR
// One lane (a CPU without SIMD): 256 slots would overflow the 64-bit slot sets, and a vector of
// one pixel has nothing over the scalar kernel, which blends instead.
void BlendTileSimd(const Frame& frame, const TileJob& job, float* rgb, SpanPruning) {
  blend_tile_scalar(frame, job, rgb);
}
#else
// The tile's Gaussians are taken kBatch at a time, in blend order ("candidates"); a candidate
// that touches a live slot (below) is a member of its batch. Per batch: the candidates' fields
// as arrays (copied from their blend_data lines, which lie anywhere), then their rows' spans a
// vector of candidates at a time, row by row (the member records and sets), then the slots.
// 32 per batch (pc_playbot 1080p, Zen 4: 64 took the blend 4% longer, 16 up to 3% longer).
constexpr int kBatch = 32;
using MemberSet = std::uint32_t;  // bit j: candidate j of the batch
static_assert(kBatch <= 32, "member sets of 32 bits");

struct BatchFields {
  HWY_ALIGN float mean_x[kBatch], mean_y[kBatch], whiten0[kBatch], whiten2[kBatch];
  HWY_ALIGN float red[kBatch], green[kBatch], blue[kBatch], log2_opacity[kBatch];
  HWY_ALIGN float row_q_coeff[kBatch], q_cut[kBatch], row_slope[kBatch], inv_conic_a[kBatch];
};

// What the blend loop reads of each member: along a row at offset dy, q is smallest at column
// x* = mean_x + row_slope dy, where it is row_q_coeff dy^2, and grows as conic_a (x - x*)^2
// (conic_a = w0^2 + w2^2): so the exponent q * -log2(e)/2 + log2 opacity is a * (x - x*)^2 + c
// with a = conic_a * -log2(e)/2 per member (`quadratic`) and c = row_q_coeff dy^2 * -log2(e)/2
// + log2 opacity per row (`offset`), three operations per pixel instead of the whitened form's
// six. Both terms are <= 0, so their sum does not cancel, and x - x* is taken in the tile's
// columns from the member's centre relative to the tile (`centre`; its float roundings are
// those of the whitened form's terms). One float each, broadcast where it is used.
struct MemberRecords {
  HWY_ALIGN float quadratic[kBatch], red[kBatch], green[kBatch], blue[kBatch];
  HWY_ALIGN float centre[gm::kTileSize][kBatch], offset[gm::kTileSize][kBatch];
};

// Candidates [begin, begin + n) of the tile into `fields`, padded to whole vectors with zeros
// (finite values; find_members leaves those lanes out). Prefetches the lines kBatch candidates
// ahead: the next batch's, which the rest of this batch's work gives time to arrive.
void copy_candidates(const Frame& frame, const TileJob& job, std::uint64_t begin, int n, int padded,
                     BatchFields& fields) {
  for (int j = 0; j < padded; ++j) {
    if (j >= n) {
      fields.mean_x[j] = fields.mean_y[j] = fields.whiten0[j] = fields.whiten2[j] = 0.0f;
      fields.red[j] = fields.green[j] = fields.blue[j] = fields.log2_opacity[j] = 0.0f;
      fields.row_q_coeff[j] = fields.q_cut[j] = fields.row_slope[j] = fields.inv_conic_a[j] = 0.0f;
      continue;
    }
    const std::uint64_t k = begin + static_cast<std::uint64_t>(j);
    if (k + kBatch < job.count) hwy::Prefetch(&frame.blend_data[job.ids[k + kBatch]]);
    const BlendGaussian& g = frame.blend_data[job.ids[k]];
    fields.mean_x[j] = g.mean_x;
    fields.mean_y[j] = g.mean_y;
    fields.whiten0[j] = g.whiten[0];
    fields.whiten2[j] = g.whiten[2];
    fields.red[j] = g.rgb[0];
    fields.green[j] = g.rgb[1];
    fields.blue[j] = g.rgb[2];
    fields.log2_opacity[j] = g.log2_opacity;
    fields.row_q_coeff[j] = g.row_q_coeff;
    fields.q_cut[j] = g.q_cut;
    fields.row_slope[j] = g.row_slope;
    fields.inv_conic_a[j] = g.inv_conic_a;
  }
}

// The tile's vectors ("slots"): lane group j of row y is slot j * kTileSize + y (16 rows x at
// most 4 groups), bit `slot` of a 64-bit set. Per slot, one vector each, next to each other
// (one base address per slot): the pixels' column in the tile, transmittance, colour, and the
// transmittance of the pixels that still blend, 0 on the finished ones (which need no mask of
// their own then) - pixels outside the image start finished. A slot whose lanes have all
// finished leaves live_slots (and slot_live, the same as a word per slot, which the span pass
// reads), and the tile stops when none is left.
static_assert(gm::kTileSize <= 16, "64 slots: 16 rows of at most 4 lane groups");
constexpr int kMaxSlots = 64;
enum SlotField { kX, kT, kRed, kGreen, kBlue, kLiveT, kSlotFields };

struct TileState {
  HWY_ALIGN float slots[kSlotFields * kTilePixels];
  MemberSet slot_live[kMaxSlots];
  std::uint64_t live_slots = 0;
  MemberSet slot_members[kMaxSlots] = {};  // per slot, the batch's members that touch it
};

// Margins of the spans below. A lane passes the exact test (alpha >= 1/255) only where its
// q = conic_a (x - x*)^2 + row_q is at most q_cut plus the test's own error: exp2's relative
// error (kSimdAlphaMaxRelError, 8e-6 in q) and the roundings of the exponent's terms (a few
// float ulps of values <= 12 where it can pass: ~1e-5 in q), while inv_conic_a, made in double,
// differs from the float conic_a the exponent uses by ~3e-7 relative. So q_cut + 1/64 in q, a
// span 2^-15 wider relative (which also covers rounding the centre plus or minus a span as
// wide as the distance to the tile) and 1/64 pixel more hold every pixel that passes, with
// more than 30x to spare, and are much tighter than the scalar kernel's 0.5 and one pixel:
// 7% fewer blend-loop visits (pc_playbot 1080p, camera 0).
constexpr float kSpanQMargin = 1.0f / 64;
constexpr float kSpanWidthScale = 1.0f + 1.0f / 16384;  // on (half width)^2
constexpr float kSpanPixelMargin = 1.0f / 64;

// Each slot whose row's span of pixels that can pass the exact test meets its lane group, and
// which is live, gets the bit of candidate j < n: a vector of candidates at a time, row by
// row. A span holds every such pixel (the margins above) and may hold a few that then fail the
// test: the same pixels blend. Also writes the members' records (whatever the candidate: one
// that touches no live slot is never read).
void find_members(const BatchFields& fields, int n, int x_begin, int y_begin, int tile_w, int tile_h,
                  float q_margin, TileState& tile, MemberRecords& records) {
  const FloatTag d;
  const int lanes = static_cast<int>(hn::Lanes(d));
  const int groups_per_row = gm::kTileSize / lanes;
  const auto zero = hn::Zero(d), one = hn::Set(d, 1.0f);
  const auto minus_half_log2e = hn::Set(d, -kHalfLog2E);
  const auto top = hn::Set(d, static_cast<float>(y_begin));
  const auto tile_left = hn::Set(d, static_cast<float>(x_begin));
  const auto tile_right = hn::Set(d, static_cast<float>(tile_w - 1));
  const auto last_tile_row = hn::Set(d, static_cast<float>(tile_h - 1));
  // The rows where some slot is live.
  std::uint32_t live_rows = 0;
  for (int v = 0; v < groups_per_row; ++v)
    live_rows |= static_cast<std::uint32_t>(tile.live_slots >> (v * gm::kTileSize)) & ((1u << gm::kTileSize) - 1u);
  for (int base = 0; base < n; base += lanes) {
    const auto candidate = hn::FirstN(d, static_cast<std::size_t>(n - base));
    const auto mean_x = hn::Load(d, fields.mean_x + base), mean_y = hn::Load(d, fields.mean_y + base);
    const auto coeff = hn::Load(d, fields.row_q_coeff + base), slope = hn::Load(d, fields.row_slope + base);
    const auto width_coeff = hn::Mul(hn::Load(d, fields.inv_conic_a + base), hn::Set(d, kSpanWidthScale));
    const auto log2_opacity = hn::Load(d, fields.log2_opacity + base);
    const auto q_reach = hn::Add(hn::Load(d, fields.q_cut + base), hn::Set(d, q_margin));
    // The candidates' row ranges, as the scalar kernel's: reach = sqrt(q_reach / coeff) + 1, or
    // everything when coeff is 0.
    const auto local_y = hn::Sub(mean_y, top);
    const auto reach = hn::IfThenElse(hn::Gt(coeff, zero), hn::Add(hn::Sqrt(hn::Div(q_reach, coeff)), one),
                                      hn::Set(d, 1e30f));
    const auto first_row = hn::Max(zero, hn::Ceil(hn::Sub(local_y, reach)));
    const auto last_row = hn::Min(last_tile_row, hn::Floor(hn::Add(local_y, reach)));
    // The rows some candidate of the vector reaches. q_reach < 0 (opacity < 1/255, drawn by the
    // baseline): no pixel passes, no row; nor for NaN rows.
    const auto reaches = hn::And(candidate, hn::And(hn::Ge(q_reach, zero), hn::Le(first_row, last_row)));
    const float lowest =
        hn::GetLane(hn::MinOfLanes(d, hn::IfThenElse(reaches, first_row, hn::Set(d, static_cast<float>(gm::kTileSize)))));
    const float highest = hn::GetLane(hn::MaxOfLanes(d, hn::IfThenElse(reaches, last_row, hn::Set(d, -1.0f))));
    if (lowest > highest) continue;
    const int row_lo = static_cast<int>(lowest), row_hi = static_cast<int>(highest);
    std::uint32_t rows = live_rows & (((2u << row_hi) - 1u) & ~((1u << row_lo) - 1u));

    const float conic_a_scale = -kHalfLog2E;
    const auto w0 = hn::Load(d, fields.whiten0 + base), w2 = hn::Load(d, fields.whiten2 + base);
    hn::Store(hn::Mul(hn::Add(hn::Mul(w0, w0), hn::Mul(w2, w2)), hn::Set(d, conic_a_scale)), d,
              records.quadratic + base);
    hn::Store(hn::Load(d, fields.red + base), d, records.red + base);
    hn::Store(hn::Load(d, fields.green + base), d, records.green + base);
    hn::Store(hn::Load(d, fields.blue + base), d, records.blue + base);
    const auto local_centre_x = hn::Sub(mean_x, tile_left);
    for (; rows != 0; rows &= rows - 1u) {
      const int row = static_cast<int>(hwy::Num0BitsBelowLS1Bit_Nonzero32(rows));
      const auto dy = hn::Sub(hn::Set(d, static_cast<float>(y_begin + row)), mean_y);
      const auto row_q = hn::Mul(hn::Mul(coeff, dy), dy);
      const auto centre = hn::Add(local_centre_x, hn::Mul(slope, dy));
      hn::Store(centre, d, records.centre[row] + base);
      hn::Store(hn::MulAdd(row_q, minus_half_log2e, log2_opacity), d, records.offset[row] + base);
      // The pixels of the row that can pass the exact test lie within `half_width` of the
      // centre. A row is touched where row_q <= q_reach (false for NaN; rows outside the
      // candidate's row range fail it too, by the range's margin).
      const auto half_width = hn::Add(hn::Sqrt(hn::Mul(hn::Max(zero, hn::Sub(q_reach, row_q)), width_coeff)),
                                      hn::Set(d, kSpanPixelMargin));
      const auto span_first = hn::Sub(centre, half_width), span_last = hn::Add(centre, half_width);
      // Group v holds columns [v lanes, (v + 1) lanes) of the tile's: the span meets it unless
      // it ends before or starts after (a span between two columns counts too: a visit whose
      // lanes all fail the test); a NaN span meets every group (its alpha fails the test).
      const auto touched = hn::And(candidate, hn::AndNot(hn::Gt(span_first, tile_right), hn::Le(row_q, q_reach)));
      for (int v = 0; v < groups_per_row; ++v) {
        const int slot = v * gm::kTileSize + row;
        const auto before = hn::Gt(span_first, hn::Set(d, static_cast<float>((v + 1) * lanes - 1)));
        const auto after = hn::Lt(span_last, hn::Set(d, static_cast<float>(v * lanes)));
        const auto meets = hn::AndNot(hn::Or(before, after), touched);
        std::uint8_t bits[(gm::kTileSize + 7) / 8] = {};
        hn::StoreMaskBits(d, meets, bits);
        const MemberSet set = (static_cast<MemberSet>(bits[0]) | (lanes > 8 ? static_cast<MemberSet>(bits[1]) << 8 : 0u));
        tile.slot_members[slot] |= (set & tile.slot_live[slot]) << base;
      }
    }
  }
}

// Blends the batch's members into the slots they touch, slot by slot: a slot's state stays in
// registers while its members blend in order, so it is loaded and stored once per batch
// instead of once per Gaussian. Per pixel the Gaussians and the operations are those of one
// Gaussian at a time, in the same order. Empties the member sets.
void blend_members(const MemberRecords& records, int slot_count, TileState& tile) {
  const FloatTag d;
  const std::size_t lanes = hn::Lanes(d);
  const auto alpha_max = hn::Set(d, gm::kAlphaMax), alpha_min = hn::Set(d, gm::kAlphaMin);
  const auto t_min = hn::Set(d, gm::kTransmittanceMin);
  // The slots some member touches.
  std::uint64_t batch_slots = 0;
  for (int slot = 0; slot < slot_count; ++slot)
    batch_slots |= static_cast<std::uint64_t>(tile.slot_members[slot] != 0) << slot;
  for (; batch_slots != 0; batch_slots &= batch_slots - 1u) {
    const int slot = static_cast<int>(hwy::Num0BitsBelowLS1Bit_Nonzero64(batch_slots));
    const int row = slot % gm::kTileSize;
    const float* centre_row = records.centre[row];
    const float* offset_row = records.offset[row];
    float* state = tile.slots + slot * kSlotFields * lanes;
    const auto x = hn::Load(d, state + kX * lanes);
    auto t = hn::Load(d, state + kT * lanes);
    auto red = hn::Load(d, state + kRed * lanes), green = hn::Load(d, state + kGreen * lanes);
    auto blue = hn::Load(d, state + kBlue * lanes);
    auto live_t = hn::Load(d, state + kLiveT * lanes);
    MemberSet members = tile.slot_members[slot];
    tile.slot_members[slot] = 0;
    // No early outs per visit (no lane above power_cut, a lane finishing): the masks below
    // make those lanes no-ops, and the branches mispredicted more than the work they saved
    // (callgrind on pc_playbot: 29% fewer mispredicts for 5% more instructions).
    for (; members != 0; members &= members - 1u) {
      const std::size_t j = hwy::Num0BitsBelowLS1Bit_Nonzero32(members);
      const auto dx = hn::Sub(x, hn::Set(d, centre_row[j]));
      const auto exponent = hn::MulAdd(hn::Mul(dx, dx), hn::Set(d, records.quadratic[j]), hn::Set(d, offset_row[j]));
      // Only the exact test: a lane outside the row's span has alpha < 1/255 for certain (the
      // spans' margins, above), so it fails this test as surely as it would have been skipped.
      // A lane that fails it gets alpha 0, which leaves its T and colour as they are, bit for
      // bit (T - 0 T = T, colour + c 0 = colour: both start at +0 or 1 and stay >= 0): no mask
      // of its own below.
      const auto unclamped = exp2_nonpositive(d, exponent);
      const auto alpha = hn::IfThenElseZero(hn::Ge(unclamped, alpha_min), hn::Min(alpha_max, unclamped));
      // T - alpha T with one rounding: the scalar kernel's T (1 - alpha) where 1 - alpha is
      // exact (alpha >= 1/2), within an ulp elsewhere, and its product is the weight. live_t is
      // a live lane's T and 0 on a finished one, whose next T, 0, is then below the minimum.
      const auto next_t = hn::NegMulAdd(alpha, live_t, live_t);
      // A live lane whose T would drop below the minimum finishes instead of blending (alpha
      // 0 never does: a live lane's T is at least the minimum); the others blend.
      const auto blends = hn::Ge(next_t, t_min);
      // Lanes that do not blend add colour * 0: the same bytes as leaving them, for one
      // select instead of three.
      const auto weight = hn::IfThenElseZero(blends, hn::Mul(alpha, live_t));
      red = hn::MulAdd(hn::Set(d, records.red[j]), weight, red);
      green = hn::MulAdd(hn::Set(d, records.green[j]), weight, green);
      blue = hn::MulAdd(hn::Set(d, records.blue[j]), weight, blue);
      t = hn::IfThenElse(blends, next_t, t);  // a finishing lane keeps its T
      live_t = hn::IfThenElseZero(blends, next_t);
    }
    hn::Store(t, d, state + kT * lanes);
    hn::Store(red, d, state + kRed * lanes);
    hn::Store(green, d, state + kGreen * lanes);
    hn::Store(blue, d, state + kBlue * lanes);
    hn::Store(live_t, d, state + kLiveT * lanes);
    if (hn::AllTrue(d, hn::Eq(live_t, hn::Zero(d)))) {
      tile.live_slots &= ~(std::uint64_t{1} << slot);
      tile.slot_live[slot] = 0;
    }
  }
}

void BlendTileSimd(const Frame& frame, const TileJob& job, float* rgb, SpanPruning pruning) {
  const FloatTag d;
  const std::size_t lanes = hn::Lanes(d);
  const int lanes_i = static_cast<int>(lanes);
  const int groups_per_row = gm::kTileSize / lanes_i;
  static_assert(hn::MaxLanes(FloatTag()) >= 4, "at most 64 slots");
  static_assert(kBatch % hn::MaxLanes(FloatTag()) == 0, "whole vectors of candidates per batch");
  const int width = frame.camera.width, height = frame.camera.height;
  const int x_begin = job.tile_x * gm::kTileSize, y_begin = job.tile_y * gm::kTileSize;
  const int tile_w = std::min(gm::kTileSize, width - x_begin);
  const int tile_h = std::min(gm::kTileSize, height - y_begin);
  // The first batch's lines, while the slots are set up.
  for (std::uint64_t k = 0; k < std::min<std::uint64_t>(kBatch, job.count); ++k)
    hwy::Prefetch(&frame.blend_data[job.ids[k]]);

  TileState tile;
  const auto slot_field = [&](int slot, SlotField field) {
    return tile.slots + (slot * kSlotFields + field) * lanes_i;
  };
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
      hn::Store(hn::IfThenElseZero(inside, hn::Set(d, 1.0f)), d, slot_field(slot, kLiveT));
      const bool any_inside = !hn::AllFalse(d, inside);
      tile.slot_live[slot] = any_inside ? ~MemberSet{0} : 0u;
      if (any_inside) tile.live_slots |= std::uint64_t{1} << slot;
    }

  BatchFields fields;
  MemberRecords records;
  // Without pruning every span holds the whole tile: q_reach and the spans are infinite.
  const float q_margin = pruning == SpanPruning::on ? kSpanQMargin : std::numeric_limits<float>::infinity();
  const int slot_count = groups_per_row * gm::kTileSize;
  for (std::uint64_t k = 0; k < job.count && tile.live_slots != 0; k += kBatch) {
    const int n = static_cast<int>(std::min<std::uint64_t>(kBatch, job.count - k));
    const int padded = (n + lanes_i - 1) / lanes_i * lanes_i;
    copy_candidates(frame, job, k, n, padded, fields);
    find_members(fields, n, x_begin, y_begin, tile_w, tile_h, q_margin, tile, records);
    blend_members(records, slot_count, tile);
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

#endif  // HWY_TARGET == HWY_SCALAR

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

void blend_tile_simd(const Frame& frame, const TileJob& tile, float* rgb, SpanPruning pruning) {
  HWY_DYNAMIC_DISPATCH(BlendTileSimd)(frame, tile, rgb, pruning);
}

void simd_alpha(const float* q, const float* log2_opacity, float* alpha, std::size_t n) {
  HWY_DYNAMIC_DISPATCH(SimdAlpha)(q, log2_opacity, alpha, n);
}

std::string simd_target_name() { return HWY_DYNAMIC_DISPATCH(TargetName)(); }

void apply_simd_target_limit(const std::string& wanted) {
  hwy::DisableTargets(0);  // what the CPU supports, whatever an earlier renderer chose
  if (wanted.empty()) return;
  std::int64_t chosen = 0;
  std::string names;
  for (const std::int64_t target : hwy::SupportedAndGeneratedTargets()) {
    names += std::string(names.empty() ? "" : ", ") + hwy::TargetName(target);
    if (strcasecmp(hwy::TargetName(target), wanted.c_str()) == 0) chosen = target;
  }
  if (chosen == 0) {
    // Once per value: a process makes several renderers.
    static std::mutex said_mutex;
    static std::string said;
    const std::lock_guard<std::mutex> lock(said_mutex);
    if (said != wanted)
      std::fprintf(stderr,
                   "cpu_simd=%s (FLASHGS_CPU_SIMD): not a SIMD target this build has and this CPU runs (%s); using the "
                   "best\n",
                   wanted.c_str(), names.c_str());
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

void blend_tile_simd(const Frame& frame, const TileJob& tile, float* rgb, SpanPruning) {
  blend_tile_scalar(frame, tile, rgb);
}

void simd_alpha(const float* q, const float* log2_opacity, float* alpha, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) alpha[i] = std::exp2(log2_opacity[i]) * std::exp(-0.5f * q[i]);
}

std::string simd_target_name() { return "scalar"; }

void apply_simd_target_limit(const std::string& wanted) {
  if (!wanted.empty())
    std::fprintf(stderr, "cpu_simd=%s (FLASHGS_CPU_SIMD): this build has no SIMD kernels (built without Highway)\n",
                 wanted.c_str());
}

}  // namespace cpu
}  // namespace flashgs
#endif
