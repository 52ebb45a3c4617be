// Stage `project` (+ fused `emit`): cull, 2D footprint, SH colour and, in the FlashGS path,
// the Gaussian-tile keys, all in one pass over the scene.
#include <math.h>

#include <algorithm>
#include <type_traits>

#include "bin_tally.cuh"
#include "bins.cuh"
#include "chunk_cull.cuh"
#include "device_common.cuh"
#include "flashgs/error.h"
#include "flashgs/gaussian_math.h"
#include "pipeline.h"
#include "scene_access.cuh"

namespace flashgs {
namespace cuda {
namespace {

constexpr int kBlock = 256;
// Blocks of the deferred-emission kernel: enough to fill an H100 several times; the ones past
// the frame's deferred count return at once.
constexpr unsigned kDeferredEmitBlocks = 1024;
constexpr float kLog2e = 1.4426950408889634f;
// Preprocess counts its pairs per bin in 16-bit halves (its shared memory holds the small
// boxes' scratch too): a block counting pairs takes one chunk, which adds at most one pair per
// Gaussian to a bin.
static_assert(kChunkSize <= 0xffff, "a packed count holds a chunk's pairs");
template <bool COUNTED>
using PreprocessTally = std::conditional_t<COUNTED, BinTally<true>, NoBinTally>;
// The deferred boxes' kernel: a word per bin (its blocks may take any number of items).
template <bool COUNTED>
using DeferredTally = std::conditional_t<COUNTED, BinTally<false>, NoBinTally>;

// Stores one pair and counts it in its bin (bin_tally.cuh).
template <typename Tally>
__device__ __forceinline__ void emit_pair(const FrameBuffers& buf, unsigned long long offset, std::uint32_t bin,
                                          std::uint32_t depth, std::uint32_t value) {
  store_pair(buf, offset, bin, depth, value);
  Tally::add(buf, bin);
}

// Higher SH bands of Gaussian i into registers: only the float4s that DEGREE needs are read,
// whatever degree the scene was stored with.
template <int DEGREE>
__device__ __forceinline__ void colour(const DeviceScene& scene, unsigned i, const gm::CameraParams& cam,
                                       const float pos[3], const float dc[3], float rgb[3]) {
  if constexpr (DEGREE == 0) {
    gm::sh_to_rgb<0>(cam.position, pos, dc, nullptr, rgb);
  } else {
    constexpr int kRest = ((DEGREE + 1) * (DEGREE + 1) - 1) * 3;
    constexpr int kVec = (kRest + 3) / 4;
    float rest[kVec * 4];
    const std::size_t first = static_cast<std::size_t>(i) * scene.rest_stride_vec4;
    if (scene.sh_half) {
      // fp16_sh: half the bytes; the conversion to float is exact, so the sum below is the CPU's.
#pragma unroll
      for (int k = 0; k < kVec; ++k) {
        const uint2 v = __ldg(scene.sh_rest_half + first + k);
        rest[4 * k + 0] = low_half(v.x);
        rest[4 * k + 1] = high_half(v.x);
        rest[4 * k + 2] = low_half(v.y);
        rest[4 * k + 3] = high_half(v.y);
      }
    } else {
#pragma unroll
      for (int k = 0; k < kVec; ++k) {
        const float4 v = __ldg(scene.sh_rest + first + k);
        rest[4 * k + 0] = v.x;
        rest[4 * k + 1] = v.y;
        rest[4 * k + 2] = v.z;
        rest[4 * k + 3] = v.w;
      }
    }
    gm::sh_to_rgb<DEGREE>(cam.position, pos, dc, rest, rgb);
  }
}

// The whole footprint of lane `src`, word by word, so that no field can be forgotten.
__device__ __forceinline__ gm::Footprint shfl_footprint(const gm::Footprint& f, int src) {
  static_assert(sizeof(gm::Footprint) % 4 == 0, "footprint is made of 32-bit words");
  constexpr int kWords = sizeof(gm::Footprint) / 4;
  unsigned words[kWords];
  memcpy(words, &f, sizeof(f));
#pragma unroll
  for (int k = 0; k < kWords; ++k) words[k] = __shfl_sync(kFullMask, words[k], src);
  gm::Footprint g;
  memcpy(&g, words, sizeof(g));
  return g;
}

// A segment of up to 32 chunks of 32 bins of a box (bins counted row-major from the box's
// first), walked by a warp: lane j handles bin s0 + 32 c + j of chunk c. A segment stops at
// the box's end or after `max_chunks` chunks. The bin's column
// and row advance by a fixed step per chunk, so only the first costs integer divisions.
struct BoxWalk {
  BinBox bins;
  unsigned box, box_w;   // bins in the box, bins per box row
  unsigned step_x, step_y;  // 32 bins further: columns and rows to add
  __device__ BoxWalk(const gm::Footprint& g, int shift)
      : bins(g, shift),
        box(bins.count()),
        box_w(static_cast<unsigned>(bins.width())),
        step_x(kWarp % box_w),
        step_y(kWarp / box_w) {}
  // The key's bin of box column x, row y.
  __device__ unsigned bin(unsigned x, unsigned y, const BinGrid& grid) const {
    return static_cast<unsigned>(bins.y0 + static_cast<int>(y)) * static_cast<unsigned>(grid.x) +
           static_cast<unsigned>(bins.x0 + static_cast<int>(x));
  }
  __device__ unsigned chunks(unsigned s0, unsigned max_chunks) const {
    return min(max_chunks, (box - s0 + kWarp - 1) / kWarp);
  }
  // Column and row (in the box) of bin s0 + lane.
  __device__ void start(unsigned s0, unsigned lane, unsigned& x, unsigned& y) const {
    const unsigned t = s0 + lane;
    x = t % box_w;
    y = t / box_w;
  }
  __device__ void advance(unsigned& x, unsigned& y) const {
    x += step_x;
    y += step_y;
    if (x >= box_w) {
      x -= box_w;
      ++y;
    }
  }
};

// The tiles of box bin (x, y) that footprint g touches (bin_tiles).
__device__ __forceinline__ unsigned walk_bin_tiles(const gm::Footprint& g, const BoxWalk& walk, int shift, unsigned x,
                                                   unsigned y, const gm::CameraParams& cam, bool exact) {
  return footprint_bin_tiles(g, shift, walk.bins.x0 + static_cast<int>(x), walk.bins.y0 + static_cast<int>(y), cam,
                             exact);
}

// Tests the segment at s0 (all lanes call with the same footprint); lane c returns chunk c's
// ballot of passing bins.
__device__ unsigned warp_test_segment(const gm::Footprint& g, const BoxWalk& walk, unsigned s0, unsigned max_chunks,
                                      const gm::CameraParams& cam, bool exact, int shift) {
  const unsigned lane = lane_id();
  const unsigned chunks = walk.chunks(s0, max_chunks);
  unsigned x, y;
  walk.start(s0, lane, x, y);
  unsigned my_ballot = 0;
  for (unsigned c = 0; c < chunks; ++c) {
    const bool pass = s0 + c * kWarp + lane < walk.box && walk_bin_tiles(g, walk, shift, x, y, cam, exact) != 0;
    const unsigned ballot = __ballot_sync(kFullMask, pass);
    if (lane == c) my_ballot = ballot;
    walk.advance(x, y);
  }
  return my_ballot;
}

// Writes the segment's passing bins; lane c holds chunk c's ballot and its first offset. With
// bins larger than a tile, a passing bin's tiles are tested again for its value (the test
// kept no more than a bit per bin).
template <typename Tally>
__device__ void warp_write_segment(const FrameBuffers& buf, const gm::Footprint& g, const BoxWalk& walk, unsigned s0,
                                   unsigned max_chunks, unsigned my_ballot, unsigned long long my_base,
                                   std::uint32_t depth_bits, unsigned record, const gm::CameraParams& cam, bool exact) {
  const unsigned lane = lane_id();
  const unsigned lanes_below = (1u << lane) - 1u;
  const unsigned chunks = walk.chunks(s0, max_chunks);
  unsigned x, y;
  walk.start(s0, lane, x, y);
  for (unsigned c = 0; c < chunks; ++c) {
    const unsigned ballot = __shfl_sync(kFullMask, my_ballot, c);
    const unsigned long long chunk_base = __shfl_sync(kFullMask, my_base, c);
    if (ballot & (1u << lane)) {
      const unsigned tiles = buf.bins.shift ? walk_bin_tiles(g, walk, buf.bins.shift, x, y, cam, exact) : 1u;
      emit_pair<Tally>(buf, chunk_base + __popc(ballot & lanes_below), walk.bin(x, y, buf.bins), depth_bits,
                       pair_value(buf.bins, record, tiles));
    }
    walk.advance(x, y);
  }
}

// The pairs of one Gaussian's box, emitted by the whole warp (all lanes call with the same
// footprint), one atomic per segment; returns how many were wanted.
template <typename Tally>
__device__ unsigned warp_emit_box(const FrameBuffers& buf, const gm::Footprint& g, std::uint32_t depth_bits,
                                  unsigned record, const gm::CameraParams& cam, bool exact) {
  const unsigned lane = lane_id();
  const BoxWalk walk(g, buf.bins.shift);
  unsigned total = 0;
  for (unsigned s0 = 0; s0 < walk.box; s0 += kWarp * kWarp) {
    const unsigned my_ballot = warp_test_segment(g, walk, s0, kWarp, cam, exact, buf.bins.shift);
    const unsigned my_count = __popc(my_ballot);
    const unsigned inclusive = warp_inclusive_sum(my_count);
    const unsigned segment_total = __shfl_sync(kFullMask, inclusive, kWarp - 1);
    if (segment_total == 0) continue;
    unsigned long long base = 0;
    if (lane == 0) base = atomicAdd(&buf.counters->pairs, static_cast<unsigned long long>(segment_total));
    base = __shfl_sync(kFullMask, base, 0) + (inclusive - my_count);  // lane c: chunk c's offset
    warp_write_segment<Tally>(buf, g, walk, s0, kWarp, my_ballot, base, depth_bits, record, cam, exact);
    total += segment_total;
  }
  return total;
}

// The small boxes of a warp's Gaussians (at most kWarp bins each), tested and emitted by the
// whole warp over their concatenation, 32 bins per step: a thread looping over its own box
// left most lanes idle while the warp's largest box finished (2-7 of 32 lanes active).
// What a lane's bin test needs of its owner is staged in shared memory.
struct alignas(16) SmallBox {
  float4 whiten;
  float edge_slope_x, edge_slope_y, threshold, mean_x;
  float mean_y;
  unsigned tiles_x, tiles_y;  // the tile box: first tile | one past the last << 16
  int box_w;                  // bins per box row
  unsigned start, row_magic, record, depth_bits;  // row_magic: ceil(2^16 / box_w), t / box_w = (t row_magic) >> 16
};
// A box in the scratch, 80 bytes apart: lanes read their owners' boxes 16 bytes at a time, and
// at a 64-byte stride every second box fell on the same banks (a quarter-warp of distinct
// owners took up to four passes); at 20 words, eight consecutive boxes take distinct banks.
struct alignas(16) BankSpreadBox {
  SmallBox box;
  unsigned pad[4];
};
static_assert(sizeof(BankSpreadBox) == 80, "a box 20 banks from the next");
constexpr int kSmallTilesPerWarp = kWarp * kWarp;

struct SmallBoxScratch {
  BankSpreadBox boxes[kWarp];
  unsigned char owner[kSmallTilesPerWarp];  // concatenated bin -> the lane whose box holds it
  unsigned char tiles[kSmallTilesPerWarp];  // concatenated bin -> the tiles it touches (bin_tiles)
};

// Bin t of the box (row-major from its first bin): t < kSmallTilesPerWarp and box_w <= kWarp
// keep (t row_magic) >> 16 exact (the magic's excess times t stays below 1/box_w).
__device__ __forceinline__ void small_box_bin(const SmallBox& b, int shift, unsigned t, int& bx, int& by) {
  const unsigned row = (t * b.row_magic) >> 16;
  bx = static_cast<int>(b.tiles_x & 0xffffu) >> shift;
  by = static_cast<int>(b.tiles_y & 0xffffu) >> shift;
  bx += static_cast<int>(t - row * static_cast<unsigned>(b.box_w));
  by += static_cast<int>(row);
}

// All lanes call; my_box: this lane's box size (0: nothing to emit here). Returns this lane's
// pair count.
template <typename Tally>
__device__ unsigned warp_emit_small_boxes(SmallBoxScratch& s, const FrameBuffers& buf, const gm::Footprint& f,
                                          unsigned my_box, std::uint32_t depth_bits, unsigned record,
                                          const gm::CameraParams& cam) {
  const unsigned lane = lane_id();
  const unsigned inclusive = warp_inclusive_sum(my_box);
  const unsigned start = inclusive - my_box, total_tiles = __shfl_sync(kFullMask, inclusive, kWarp - 1);
  if (total_tiles == 0) return 0;
  const int shift = buf.bins.shift;
  if (my_box > 0) {
    const int box_w = BinBox(f, shift).width();
    s.boxes[lane].box = SmallBox{make_float4(f.whiten[0], f.whiten[1], f.whiten[2], f.whiten[3]),
                             f.edge_slope_x, f.edge_slope_y, f.threshold, f.mean_x, f.mean_y,
                             static_cast<unsigned>(f.tile_x0) | static_cast<unsigned>(f.tile_x1) << 16,
                             static_cast<unsigned>(f.tile_y0) | static_cast<unsigned>(f.tile_y1) << 16,
                             box_w, start, (65536u + static_cast<unsigned>(box_w) - 1u) / static_cast<unsigned>(box_w),
                             record, depth_bits};
    for (unsigned t = 0; t < my_box; ++t) s.owner[start + t] = static_cast<unsigned char>(lane);
  }
  __syncwarp();
  // Test: lane c keeps step c's ballot.
  const unsigned steps = (total_tiles + kWarp - 1) / kWarp;
  unsigned my_ballot = 0;
  for (unsigned c = 0; c < steps; ++c) {
    const unsigned g = c * kWarp + lane;
    bool pass = false;
    if (g < total_tiles) {
      const SmallBox& b = s.boxes[s.owner[g]].box;
      int bx, by;
      small_box_bin(b, shift, g - b.start, bx, by);
      const float w[4] = {b.whiten.x, b.whiten.y, b.whiten.z, b.whiten.w};
      const unsigned tiles = bin_tiles(shift, bx, by, static_cast<int>(b.tiles_x & 0xffffu),
                                       static_cast<int>(b.tiles_y & 0xffffu), static_cast<int>(b.tiles_x >> 16),
                                       static_cast<int>(b.tiles_y >> 16), [&](int tx, int ty) {
                                         return gm::ellipse_touches_tile(w, b.edge_slope_x, b.edge_slope_y,
                                                                         b.threshold, b.mean_x, b.mean_y, tx, ty,
                                                                         cam.width, cam.height);
                                       });
      s.tiles[g] = static_cast<unsigned char>(tiles);
      pass = tiles != 0;
    }
    const unsigned ballot = __ballot_sync(kFullMask, pass);
    if (lane == c) my_ballot = ballot;
  }
  // This lane's count: the bits of its range [start, start + my_box), in at most two steps.
  unsigned my_count = 0;
  {
    const unsigned first_step = start / kWarp, last_step = (start + (my_box > 0 ? my_box : 1) - 1) / kWarp;
    const unsigned b0 = __shfl_sync(kFullMask, my_ballot, first_step & (kWarp - 1));
    const unsigned b1 = __shfl_sync(kFullMask, my_ballot, last_step & (kWarp - 1));
    if (my_box > 0) {
      const unsigned lo = start % kWarp;
      if (first_step == last_step) {
        const unsigned mask = (my_box == kWarp ? 0xffffffffu : ((1u << my_box) - 1u)) << lo;
        my_count = __popc(b0 & mask);
      } else {
        my_count = __popc(b0 & (0xffffffffu << lo)) + __popc(b1 & ((1u << ((start + my_box) % kWarp)) - 1u));
      }
    }
  }
  // One atomic for the warp, then each step's pairs at its offset.
  const unsigned step_count = __popc(my_ballot);
  const unsigned step_inclusive = warp_inclusive_sum(step_count);
  const unsigned total = __shfl_sync(kFullMask, step_inclusive, kWarp - 1);
  if (total == 0) return my_count;
  unsigned long long base = 0;
  if (lane == 0) base = atomicAdd(&buf.counters->pairs, static_cast<unsigned long long>(total));
  base = __shfl_sync(kFullMask, base, 0) + (step_inclusive - step_count);  // lane c: step c's offset
  const unsigned lanes_below = (1u << lane) - 1u;
  for (unsigned c = 0; c < steps; ++c) {
    const unsigned ballot = __shfl_sync(kFullMask, my_ballot, c);
    const unsigned long long step_base = __shfl_sync(kFullMask, base, c);
    if (ballot & (1u << lane)) {
      const unsigned g = c * kWarp + lane;
      const SmallBox& b = s.boxes[s.owner[g]].box;
      int bx, by;
      small_box_bin(b, shift, g - b.start, bx, by);
      emit_pair<Tally>(buf, step_base + __popc(ballot & lanes_below),
                       static_cast<unsigned>(by) * static_cast<unsigned>(buf.bins.x) + static_cast<unsigned>(bx),
                       b.depth_bits, pair_value(buf.bins, b.record, s.tiles[g]));
    }
  }
  __syncwarp();  // the scratch is free again
  return my_count;
}

// One chunk, a thread per Gaussian, for a chunk whose verdict is kChunkProject or
// kChunkClassify (the same for the whole block). FUSED: keys are written here (FlashGS);
// otherwise the footprint and the pair count are stored for the separate prefix sum +
// duplicate pass (3DGS).
template <int DEGREE, bool FUSED, typename Tally>
__device__ void preprocess_chunk(const DeviceScene& scene, const FrameBuffers& buf, const PreprocessArgs& args,
                                 unsigned chunk_index, int chunk) {
  __shared__ unsigned block_counts[gm::kCullReasonCount];  // by gm::CullReason
  if (threadIdx.x < gm::kCullReasonCount) block_counts[threadIdx.x] = 0;
  __syncthreads();

  const unsigned i = chunk_index * kBlock + threadIdx.x;
  const unsigned lane = lane_id();
  const bool valid = scene.draw_chunks ? threadIdx.x < scene.chunks[chunk_index].members : i < scene.count;
  const gm::CameraParams& cam = args.camera;

  if (chunk == kChunkClassify) {  // the whole block: only the centre and opacity are read
    int reason = gm::kCulledOffscreen;
    if (valid) {
      const float4 po = load_position_opacity(scene, i);
      const float pos[3] = {po.x, po.y, po.z};
      float view[3];
      gm::to_view(cam, pos, view);
      const gm::CullReason by_centre = gm::cull_by_centre(args.geometry, view, po.w);
      reason = by_centre == gm::kVisible ? gm::kCulledOffscreen : by_centre;
      if constexpr (!FUSED) buf.pair_counts[i] = 0;
    }
    // One shared atomic per reason and warp: a chunk's lanes mostly share one reason, and
    // same-address atomics from a warp serialise.
    for (int r = gm::kCulledNear; r < gm::kCullReasonCount; ++r) {
      const unsigned votes = __ballot_sync(kFullMask, valid && reason == r);
      if (lane == 0 && votes) atomicAdd(&block_counts[r], static_cast<unsigned>(__popc(votes)));
    }
    __syncthreads();
    if (threadIdx.x < gm::kCullReasonCount && block_counts[threadIdx.x] > 0)
      atomicAdd(&buf.counters->by_reason[threadIdx.x], block_counts[threadIdx.x]);
    if (threadIdx.x == 0)
      atomicAdd(&buf.counters->chunk_culled,
                static_cast<unsigned long long>(chunk_members(scene, scene.chunks, chunk_index)));
    return;
  }

  gm::Footprint f{};
  int reason = gm::kCulledDegenerate;
  unsigned count = 0;          // pairs of this Gaussian (small path / separate path)
  unsigned passed_mask = 0;    // bins of a box of <= 32 bins that passed the exact test
  bool large = false;          // emitted by a whole warp (deferred_emit_kernel, or below)
  // The flash path: boxes of at most large_box_tiles <= 32 tiles tested by the whole warp.
  const bool balanced = FUSED && args.warp_cooperative && args.exact_tile_test && args.large_box_tiles <= kWarp;
  const int shift = buf.bins.shift;
  unsigned small_box = 0;
  GaussianShape g{};
  if (valid) {
    g = load_shape(scene, i);
    reason = gm::project(cam, args.geometry, g.position, g.scale, g.quaternion, g.opacity, f);
  }
  const bool visible = reason == gm::kVisible;  // (valid)
  // This Gaussian's blend record, the value of its pairs: claimed by the warp with one atomic
  // when records are compact, else its id.
  unsigned record = i;
  if (buf.record_ids) {
    const unsigned ballot = __ballot_sync(kFullMask, visible);
    unsigned base = 0;
    if (ballot && lane == static_cast<unsigned>(__ffs(ballot) - 1)) base = atomicAdd(&buf.counters->records, __popc(ballot));
    base = __shfl_sync(kFullMask, base, ballot ? __ffs(ballot) - 1 : 0);
    record = base + __popc(ballot & ((1u << lane) - 1u));
  }
  if (visible && record < buf.record_capacity) {
    const float2 gb = __ldg(scene.dc_gb + i);
    const float dc[3] = {g.dc_red, gb.x, gb.y};
    float rgb[3];
    colour<DEGREE>(scene, i, cam, g.position, dc, rgb);
    if (buf.record_ids) buf.record_ids[record] = scene.scene_ids ? __ldg(scene.scene_ids + i) : i;
    float4* out = reinterpret_cast<float4*>(buf.blend + record);
    if (args.exp2_alpha) {
      // w' = sqrt(log2(e) / 2) w, so o e^(-q/2) = exp2(log2 o - (u'^2 + v'^2)): one exp2.
      const float hs = sqrtf(0.5f * kLog2e);
      out[0] = make_float4(f.mean_x, f.mean_y, hs * f.whiten[0], hs * f.whiten[1]);
      out[1] = make_float4(hs * f.whiten[2], hs * f.whiten[3], log2f(f.opacity), rgb[0]);
    } else {
      out[0] = make_float4(f.mean_x, f.mean_y, f.whiten[0], f.whiten[1]);
      out[1] = make_float4(f.whiten[2], f.whiten[3], f.opacity, rgb[0]);
    }
    // Rows farther than reach_y from the centre have q > 2 ln(255 o), i.e. alpha < 1/255
    // (min over dx of q at offset dy is dy^2 / Sigma_yy); the margins cover rounding, so
    // the blend may skip them without changing a pixel.
    const float det_w = f.whiten[0] * f.whiten[3] - f.whiten[1] * f.whiten[2];
    const float q_cut = 2.0f * logf(255.0f * f.opacity) + 0.01f;
    const float conic_a = f.whiten[0] * f.whiten[0] + f.whiten[2] * f.whiten[2];
    float reach_y = q_cut > 0.0f ? sqrtf(q_cut * conic_a) / fabsf(det_w) + 0.01f : -1.0f;
    if (!(reach_y < 1e30f) && q_cut > 0.0f) reach_y = 1e30f;  // degenerate: never skip
    out[2] = make_float4(rgb[1], rgb[2], reach_y, f.depth);
  }
  // A frame whose records overflowed still counts (and writes) its pairs: it runs again.
  if (visible) {
    const BinBox bins(f, shift);
    const unsigned box = bins.count();
    if (FUSED && args.warp_cooperative && box > static_cast<unsigned>(args.large_box_tiles)) {
      large = true;
    } else if (!args.exact_tile_test) {
      count = box;
    } else if (balanced) {
      small_box = box;
    } else {
      unsigned k = 0;
      for (int by = bins.y0; by < bins.y1; ++by)
        for (int bx = bins.x0; bx < bins.x1; ++bx, ++k)
          if (footprint_bin_tiles(f, shift, bx, by, cam, true) != 0) {
            ++count;
            if (k < 32) passed_mask |= 1u << k;
          }
    }
  }

  if constexpr (FUSED) {
    const std::uint32_t depth_bits = sort_depth(buf.key_format, f.depth);
    __shared__ SmallBoxScratch small_scratch[kBlock / kWarp];
    if (balanced)
      count = warp_emit_small_boxes<Tally>(small_scratch[threadIdx.x / kWarp], buf, f, small_box, depth_bits, record,
                                           cam);
    // Thread-emitted Gaussians: one atomic per warp reserves all their pairs.
    const unsigned inclusive = warp_inclusive_sum(balanced ? 0u : count);
    const unsigned warp_total = __shfl_sync(kFullMask, inclusive, kWarp - 1);
    unsigned long long base = 0;
    if (lane == kWarp - 1 && warp_total > 0) base = atomicAdd(&buf.counters->pairs, warp_total);
    base = __shfl_sync(kFullMask, base, kWarp - 1);
    if (!balanced && count > 0) {
      unsigned long long offset = base + inclusive - count;
      const BinBox bins(f, shift);
      auto store = [&](int bx, int by, unsigned tiles) {
        emit_pair<Tally>(buf, offset++, static_cast<unsigned>(by) * buf.bins.x + bx, depth_bits,
                         pair_value(buf.bins, record, tiles));
      };
      if (args.exact_tile_test && bins.count() <= 32) {
        for (unsigned m = passed_mask; m; m &= m - 1) {
          const unsigned k = __ffs(m) - 1;
          const int bx = bins.x0 + static_cast<int>(k % bins.width()), by = bins.y0 + static_cast<int>(k / bins.width());
          store(bx, by, shift ? footprint_bin_tiles(f, shift, bx, by, cam, true) : 1u);
        }
      } else {
        for (int by = bins.y0; by < bins.y1; ++by)
          for (int bx = bins.x0; bx < bins.x1; ++bx) {
            const unsigned tiles = footprint_bin_tiles(f, shift, bx, by, cam, args.exact_tile_test);
            if (tiles) store(bx, by, tiles);
          }
      }
    }
    // Large Gaussians: the warp tests 32 tiles at a time (FlashGS section 4.3), in
    // deferred_emit_kernel, which takes their boxes in work items: one atomic per warp reserves
    // its entries, one its items.
    const unsigned large_ballot = __ballot_sync(kFullMask, large);
    if (large_ballot) {
      const unsigned chunks = large ? (BinBox(f, shift).count() + kWarp - 1) / kWarp : 0u;
      const unsigned my_items = (chunks + args.item_chunks - 1) / args.item_chunks;
      const unsigned items_inclusive = warp_inclusive_sum(my_items);
      const unsigned warp_items = __shfl_sync(kFullMask, items_inclusive, kWarp - 1);
      const int leader = __ffs(large_ballot) - 1;
      unsigned entry_base = 0;
      unsigned long long item_base = 0;
      if (static_cast<int>(lane) == leader) {
        entry_base = atomicAdd(&buf.counters->deferred, __popc(large_ballot));
        item_base = atomicAdd(&buf.counters->deferred_items, static_cast<unsigned long long>(warp_items));
      }
      entry_base = __shfl_sync(kFullMask, entry_base, leader);
      item_base = __shfl_sync(kFullMask, item_base, leader);
      if (large) {
        const DeferredList& list = buf.deferred;
        const unsigned entry = entry_base + __popc(large_ballot & ((1u << lane) - 1u));
        const unsigned long long first_item = item_base + items_inclusive - my_items;
        const bool fits = entry < list.capacity && first_item + my_items <= list.item_capacity;
        if (fits) {
          list.footprints[entry] = f;
          list.records[entry] = record;
          list.hits[entry] = 0;
          large = false;  // counted as off screen below until one of its items emits a pair
        }
        // Every item reserved within the capacity is written, so the kernel reads no stale one.
        for (unsigned j = 0; j < my_items && first_item + j < list.item_capacity; ++j)
          list.items[first_item + j] = make_uint2(fits ? entry : kNoDeferredEntry, j * args.item_chunks);
      }
    }
    unsigned pending = __ballot_sync(kFullMask, large);  // the list was full: emitted here
    while (pending) {
      const int src = __ffs(pending) - 1;
      pending &= pending - 1;
      const gm::Footprint g = shfl_footprint(f, src);
      const std::uint32_t g_depth = __shfl_sync(kFullMask, depth_bits, src);
      const unsigned g_record = __shfl_sync(kFullMask, record, src);
      const unsigned total = warp_emit_box<Tally>(buf, g, g_depth, g_record, cam, args.exact_tile_test);
      if (static_cast<int>(lane) == src) count = total;
    }
  } else {
    if (valid) {
      buf.pair_counts[i] = count;
      if (count > 0) buf.footprints[i] = f;
    }
    const unsigned warp_total = __reduce_add_sync(kFullMask, count);
    if (lane == 0 && warp_total > 0) atomicAdd(&buf.counters->pairs, static_cast<unsigned long long>(warp_total));
  }

  if (valid) {
    // A box that met the image around an ellipse that met no tile counts as off screen, and so
    // does a deferred one until deferred_emit_kernel finds a tile it touches.
    const int slot = reason == gm::kVisible && count == 0 ? gm::kCulledOffscreen : reason;
    atomicAdd(&block_counts[slot], 1u);
  }
  __syncthreads();
  if (threadIdx.x < gm::kCullReasonCount && block_counts[threadIdx.x] > 0)
    atomicAdd(&buf.counters->by_reason[threadIdx.x], block_counts[threadIdx.x]);
}

// Blocks of fused preprocess an SM should hold: the kernel is latency-bound (1.2 eligible
// warps per scheduler at 3 blocks of 80 registers, pc_playbot 1080p on an H200), and 4 blocks
// (64 registers, a few bytes spilled) made the project stage up to 14 us shorter there
// (docs/PERFORMANCE.md). Degree 3 (108 registers unbounded) and the separate-emission
// kernel keep the compiler's choice.
template <int DEGREE, bool FUSED>
constexpr int kPreprocessBlocksPerSm = FUSED && DEGREE < 3 ? 4 : 1;

// A block per chunk (kChunkSize Gaussians), which tests its own chunk; LISTED (launch_chunk_list
// ran first): a grid over the listed chunks, every gridDim-th. COUNTED: the frame's pairs are
// counted per bin (bin_tally.cuh; fused emission of a block's own chunk only). One instance of
// the chunk's code per kernel: with both in one kernel the compiler spilled more, and the
// project stage took 7-9 us longer on pc_playbot (docs/PERFORMANCE.md).
template <int DEGREE, bool FUSED, bool LISTED, bool COUNTED>
__global__ void __launch_bounds__(kBlock, kPreprocessBlocksPerSm<DEGREE, FUSED>)
    preprocess_kernel(DeviceScene scene, FrameBuffers buf, PreprocessArgs args) {
  static_assert(kBlock == kChunkSize, "a block is one chunk");
  static_assert((FUSED && !LISTED) || !COUNTED, "pairs are counted per bin by fused emission of a block's chunk");
  using Tally = PreprocessTally<COUNTED>;
  if constexpr (LISTED) {
    const unsigned listed = buf.counters->listed_chunks;
    for (unsigned k = blockIdx.x; k < listed; k += gridDim.x) {
      const unsigned entry = buf.chunk_list[k];
      preprocess_chunk<DEGREE, FUSED, Tally>(scene, buf, args, entry >> 1,
                                             (entry & 1u) ? kChunkClassify : kChunkProject);
      __syncthreads();  // the chunk's shared counts are reset by the next one
    }
  } else {
    __shared__ int chunk;  // ChunkVerdict
    if (threadIdx.x == 0) {
      chunk = args.chunk_cull ? chunk_verdict(scene.chunks[blockIdx.x], args.camera, args.geometry, args.chunk_frame)
                              : kChunkProject;
      if (chunk == kChunkAllNear || chunk == kChunkAllOffscreen) {  // counted without reading a Gaussian
        const unsigned members = scene.chunks[blockIdx.x].members;
        atomicAdd(&buf.counters->by_reason[chunk == kChunkAllNear ? gm::kCulledNear : gm::kCulledOffscreen], members);
        atomicAdd(&buf.counters->chunk_culled, static_cast<unsigned long long>(members));
      }
    }
    __syncthreads();
    if (chunk == kChunkAllNear || chunk == kChunkAllOffscreen) {
      if constexpr (!FUSED) {
        const unsigned i = blockIdx.x * kBlock + threadIdx.x;
        if (i < scene.count) buf.pair_counts[i] = 0;
      }
      return;
    }
    // preprocess_chunk's first barrier comes before its first counted pair, its last after them.
    Tally::clear(buf);
    preprocess_chunk<DEGREE, FUSED, Tally>(scene, buf, args, blockIdx.x, chunk);
    Tally::flush(buf);
  }
}

// The deferred Gaussians' work items: a warp per item, spread over every warp of the grid. A
// warp tests up to kItemBatch items before it reserves all their pairs with one atomic: a
// wait on the contended pair counter for each item held the kernel back. The first item of
// an entry to emit a pair moves its Gaussian from off screen (preprocess's count) to visible.
constexpr int kItemBatch = 4;
template <bool COUNTED>
__global__ void __launch_bounds__(kBlock) deferred_emit_kernel(FrameBuffers buf, gm::CameraParams cam, bool exact,
                                                               unsigned item_chunks) {
  const DeferredList& list = buf.deferred;
  const unsigned count =
      static_cast<unsigned>(min(buf.counters->deferred_items, static_cast<unsigned long long>(list.item_capacity)));
  constexpr unsigned kWarps = kBlock / kWarp;
  const unsigned lane = lane_id();
  const unsigned stride = gridDim.x * kWarps;
  const int shift = buf.bins.shift;
  using Tally = DeferredTally<COUNTED>;
  Tally::clear(buf);
  if constexpr (COUNTED) __syncthreads();
  unsigned newly_visible = 0;
  for (unsigned k0 = blockIdx.x * kWarps + threadIdx.x / kWarp; k0 < count; k0 += kItemBatch * stride) {
    uint2 items[kItemBatch];
    unsigned my_ballot[kItemBatch], my_offset[kItemBatch];  // lane c: chunk c's ballot, offset in the batch
    unsigned batch_total = 0;
#pragma unroll
    for (int j = 0; j < kItemBatch; ++j) {
      const unsigned k = k0 + j * stride;
      items[j] = k < count ? list.items[k] : make_uint2(kNoDeferredEntry, 0);
      my_ballot[j] = 0;
      if (items[j].x != kNoDeferredEntry) {
        const gm::Footprint f = list.footprints[items[j].x];
        my_ballot[j] = warp_test_segment(f, BoxWalk(f, shift), items[j].y * kWarp, item_chunks, cam, exact, shift);
      }
      const unsigned my_count = __popc(my_ballot[j]);
      const unsigned inclusive = warp_inclusive_sum(my_count);
      my_offset[j] = batch_total + inclusive - my_count;
      batch_total += __shfl_sync(kFullMask, inclusive, kWarp - 1);
    }
    if (batch_total == 0) continue;
    unsigned long long base = 0;
    if (lane == 0) base = atomicAdd(&buf.counters->pairs, static_cast<unsigned long long>(batch_total));
    base = __shfl_sync(kFullMask, base, 0);
#pragma unroll
    for (int j = 0; j < kItemBatch; ++j) {
      if (!__any_sync(kFullMask, my_ballot[j] != 0)) continue;  // nothing passed, or no item
      const unsigned entry = items[j].x;
      const gm::Footprint f = list.footprints[entry];
      warp_write_segment<Tally>(buf, f, BoxWalk(f, shift), items[j].y * kWarp, item_chunks, my_ballot[j],
                         base + my_offset[j], sort_depth(buf.key_format, f.depth), list.records[entry], cam, exact);
      if (lane == 0 && atomicExch(&list.hits[entry], 1u) == 0) ++newly_visible;
    }
  }
  if (lane == 0 && newly_visible) {
    atomicAdd(&buf.counters->by_reason[gm::kVisible], newly_visible);
    atomicSub(&buf.counters->by_reason[gm::kCulledOffscreen], newly_visible);
  }
  if constexpr (COUNTED) {
    __syncthreads();
    Tally::flush(buf);
  }
}

// Blocks of a preprocess grid over a chunk list: a few waves' worth (the list's length is
// known on the device only), each walking every gridDim-th listed chunk.
unsigned list_grid_blocks() {
  static const unsigned blocks = [] {
    int device = 0, sms = 0;
    check_cuda(cudaGetDevice(&device), "device query");
    check_cuda(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, device), "device query");
    return static_cast<unsigned>(std::max(1, sms) * 16);
  }();
  return blocks;
}

// Launches Kernel with the shared memory of its bin tally (bin_tally.cuh). The first launch of
// a counting kernel allows it the most a tally may take: preprocess's static scratch and a 4K
// frame's tally together pass the 48 KB of the default.
template <typename Tally, auto Kernel, typename... Args>
void launch_with_tally(unsigned blocks, const FrameBuffers& buffers, cudaStream_t stream, Args... args) {
  if constexpr (!std::is_same_v<Tally, NoBinTally>) {
    static const bool allowed = [] {
      check_cuda(cudaFuncSetAttribute(Kernel, cudaFuncAttributeMaxDynamicSharedMemorySize,
                                      static_cast<int>(Tally::bytes(kBinSortMaxBins))),
                 "bin tally shared memory");
      return true;
    }();
    (void)allowed;
  }
  const unsigned bins = static_cast<unsigned>(buffers.bins.x) * static_cast<unsigned>(buffers.bins.y);
  Kernel<<<blocks, kBlock, Tally::bytes(bins), stream>>>(args...);
}

template <bool FUSED, bool LISTED, bool COUNTED>
void launch_for_degree(const DeviceScene& scene, const FrameBuffers& buffers, const PreprocessArgs& args,
                       cudaStream_t stream) {
  const unsigned chunks = static_cast<unsigned>((scene.count + kBlock - 1) / kBlock);
  const unsigned blocks = LISTED ? std::min(chunks, list_grid_blocks()) : chunks;
  using Tally = PreprocessTally<COUNTED>;
  switch (args.sh_degree) {
    case 0:
      launch_with_tally<Tally, preprocess_kernel<0, FUSED, LISTED, COUNTED>>(blocks, buffers, stream, scene, buffers, args);
      break;
    case 1:
      launch_with_tally<Tally, preprocess_kernel<1, FUSED, LISTED, COUNTED>>(blocks, buffers, stream, scene, buffers, args);
      break;
    case 2:
      launch_with_tally<Tally, preprocess_kernel<2, FUSED, LISTED, COUNTED>>(blocks, buffers, stream, scene, buffers, args);
      break;
    default:
      launch_with_tally<Tally, preprocess_kernel<3, FUSED, LISTED, COUNTED>>(blocks, buffers, stream, scene, buffers, args);
      break;
  }
}

}  // namespace

void launch_preprocess(const DeviceScene& scene, const FrameBuffers& buffers, const PreprocessArgs& args,
                       bool fused, cudaStream_t stream) {
  if (scene.count == 0) return;
  const bool counted = buffers.emitted_bin_counts != nullptr;
  if ((!fused && buffers.chunk_list) || (counted && (!fused || buffers.chunk_list)))
    throw Error("cuda renderer: internal error, a chunk list or pairs counted per bin where preprocess takes none");
  if (scene.draw_chunks && (!fused || !buffers.chunk_list))
    throw Error("cuda renderer: internal error, a pooled scene drawn without its chunk list");
  if (fused) {
    if (buffers.chunk_list) {
      launch_chunk_list(scene, buffers, args, stream);
      launch_for_degree<true, true, false>(scene, buffers, args, stream);
    } else if (counted) {
      launch_for_degree<true, false, true>(scene, buffers, args, stream);
    } else {
      launch_for_degree<true, false, false>(scene, buffers, args, stream);
    }
    if (args.warp_cooperative && buffers.deferred.capacity > 0 && buffers.deferred.item_capacity > 0) {
      const unsigned item_chunks = static_cast<unsigned>(args.item_chunks);
      if (counted)
        launch_with_tally<DeferredTally<true>, deferred_emit_kernel<true>>(
            kDeferredEmitBlocks, buffers, stream, buffers, args.camera, args.exact_tile_test, item_chunks);
      else
        launch_with_tally<DeferredTally<false>, deferred_emit_kernel<false>>(
            kDeferredEmitBlocks, buffers, stream, buffers, args.camera, args.exact_tile_test, item_chunks);
    }
  } else {
    launch_for_degree<false, false, false>(scene, buffers, args, stream);
  }
  check_cuda(cudaGetLastError(), "preprocess kernel launch");
}

}  // namespace cuda
}  // namespace flashgs
