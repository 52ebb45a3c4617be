// Stage `ranges`: each bin's [start, end) in the sorted pairs, the blend's bin order (fullest
// first), and runs of equal keys put in (depth, Gaussian id) order, so the blend order is
// exactly the CPU's whatever the key format: equal 64-bit keys share their depth (the atomics
// of emission shuffled their records), equal compact keys share a quantised depth bin. (A
// bin is a tile, or 2x2 tiles with macro bins: pipeline.h, BinGrid.)
#include <algorithm>

#include "bins.cuh"
#include "device_common.cuh"
#include "pipeline.h"
#include "sort_order.cuh"

namespace flashgs {
namespace cuda {
namespace {

constexpr int kBlock = 256;

// KEY: std::uint64_t (tile << 32 | depth bits) or std::uint32_t (tile << depth_bits | bin).
template <typename KEY>
__global__ void __launch_bounds__(kBlock) ranges_kernel(std::uint64_t pairs, const KEY* __restrict__ keys,
                                                        int tile_shift, std::uint32_t* __restrict__ values,
                                                        Records records, uint2* tile_ranges) {
  const std::uint64_t i = static_cast<std::uint64_t>(blockIdx.x) * kBlock + threadIdx.x;
  if (i >= pairs) return;
  const KEY key = keys[i];
  const std::uint32_t tile = static_cast<std::uint32_t>(key >> tile_shift);
  if (i == 0 || static_cast<std::uint32_t>(keys[i - 1] >> tile_shift) != tile)
    tile_ranges[tile].x = static_cast<unsigned>(i);
  if (i + 1 == pairs || static_cast<std::uint32_t>(keys[i + 1] >> tile_shift) != tile)
    tile_ranges[tile].y = static_cast<unsigned>(i + 1);
  const bool run_start = i == 0 || keys[i - 1] != key;
  if (run_start && i + 1 < pairs && keys[i + 1] == key) {
    std::uint64_t end = i + 2;
    while (end < pairs && keys[end] == key) ++end;
    sort_run(values + i, static_cast<unsigned>(end - i), records);
  }
}

// The largest end - start over the tiles and their sum: warp reductions, one atomic each per warp.
__global__ void __launch_bounds__(kBlock) tile_max_kernel(std::uint64_t tiles, const uint2* __restrict__ tile_ranges,
                                                          FrameCounters* counters) {
  const std::uint64_t t = static_cast<std::uint64_t>(blockIdx.x) * kBlock + threadIdx.x;
  const uint2 range = t < tiles ? tile_ranges[t] : make_uint2(0, 0);
  const unsigned warp_max = __reduce_max_sync(kFullMask, range.y - range.x);
  const unsigned warp_sum = __reduce_add_sync(kFullMask, range.y - range.x);
  if (lane_id() == 0 && warp_max > 0) {
    atomicMax(&counters->tile_totals.max_tile_pairs, warp_max);
    atomicAdd(&counters->tile_totals.tile_pairs, static_cast<unsigned long long>(warp_sum));
  }
}

// The tile-list pass (bins.cuh, write_bin_lists). A warp lists a small bin alone; a dense bin
// gets a block whose warps take a share each, so that a bin of 10^4 values costs a few runs per
// warp rather than one warp's serial walk.
constexpr int kListWarps = 8;
constexpr unsigned kSmallBin = 2 * kWarpRun;  // values of a bin one warp lists alone

// What both tile-list kernels read and write (FrameBuffers' fields of the same names).
struct BinListArgs {
  BinGrid bins;
  int tiles_x, tiles_y;
  const uint2* bin_ranges;       // tile_ranges: per bin
  const std::uint32_t* values;   // the sorted pair values
  std::uint32_t* top_lists;      // tile_values[0]
  std::uint32_t* bottom_lists;   // tile_values[1]
  uint2* tile_lists;
  std::uint32_t* dense_bins;
  FrameCounters* counters;
};

// Binned frames: each tile's list, the records of its bin's values that carry its bit, in
// bin order. A warp per bin lists the small bins and leaves the dense ones to
// dense_bin_lists_kernel (FrameBuffers::dense_bins).
__global__ void __launch_bounds__(kListWarps * kWarp) small_bin_lists_kernel(BinListArgs a) {
  static_assert(kMacroBinShift == 1, "a bin is 2x2 tiles");
  const unsigned bin = blockIdx.x * kListWarps + threadIdx.x / kWarp, lane = lane_id();
  if (bin >= static_cast<unsigned>(a.bins.x) * static_cast<unsigned>(a.bins.y)) return;  // whole warp
  const uint2 range = a.bin_ranges[bin];
  const BinLists lists{a.top_lists, a.bottom_lists, range.x, range.y - range.x};
  if (lists.length > kSmallBin) {
    if (lane == 0) a.dense_bins[atomicAdd(&a.counters->dense_bins, 1u)] = bin;
    return;
  }
  unsigned total[4];
  write_bin_lists<1>(a.values + range.x, lists, nullptr, total);
  record_tile_list(a.bins, a.tiles_x, a.tiles_y, a.tile_lists, bin, lists, total, lane);
}

// The dense bins' lists, a block per bin. Blocks beyond the listed bins return at once.
__global__ void __launch_bounds__(kListWarps * kWarp) dense_bin_lists_kernel(BinListArgs a) {
  if (blockIdx.x >= a.counters->dense_bins) return;  // whole block
  __shared__ unsigned warp_counts[kListWarps][4];
  const unsigned bin = a.dense_bins[blockIdx.x];
  const uint2 range = a.bin_ranges[bin];
  const BinLists lists{a.top_lists, a.bottom_lists, range.x, range.y - range.x};
  unsigned total[4];
  write_bin_lists<kListWarps>(a.values + range.x, lists, warp_counts, total);
  record_tile_list(a.bins, a.tiles_x, a.tiles_y, a.tile_lists, bin, lists, total, threadIdx.x);
}

// A tile's class: the leading zeros of its pair count, so fuller tiles come first.
__device__ __forceinline__ unsigned tile_class(uint2 range) { return __clz(range.y - range.x); }

// Each tile's place within its class: one atomic per class present in the warp.
__global__ void __launch_bounds__(kBlock) tile_places_kernel(std::uint64_t tiles, const uint2* __restrict__ tile_ranges,
                                                             std::uint32_t* __restrict__ places,
                                                             FrameCounters* counters) {
  const std::uint64_t t = static_cast<std::uint64_t>(blockIdx.x) * kBlock + threadIdx.x;
  const bool real = t < tiles;
  const unsigned cls = real ? tile_class(tile_ranges[t]) : kTileClasses;  // kTileClasses: no tile
  const unsigned peers = __match_any_sync(kFullMask, cls);
  const unsigned leader = __ffs(peers) - 1;
  unsigned base = 0;
  if (real && lane_id() == leader) base = atomicAdd(&counters->tiles_by_class[cls], __popc(peers));
  base = __shfl_sync(kFullMask, base, leader);
  if (real) places[t] = base + __popc(peers & ((1u << lane_id()) - 1u));
}

// tile_order[start of the tile's class + its place] = tile.
__global__ void __launch_bounds__(kBlock) tile_order_kernel(std::uint64_t tiles, const uint2* __restrict__ tile_ranges,
                                                            const std::uint32_t* __restrict__ places,
                                                            const FrameCounters* __restrict__ counters,
                                                            std::uint32_t* __restrict__ order) {
  __shared__ unsigned class_start[kTileClasses];
  if (threadIdx.x == 0) {
    unsigned start = 0;
    for (int c = 0; c < kTileClasses; ++c) {
      class_start[c] = start;
      start += counters->tiles_by_class[c];
    }
  }
  __syncthreads();
  const std::uint64_t t = static_cast<std::uint64_t>(blockIdx.x) * kBlock + threadIdx.x;
  if (t < tiles) order[class_start[tile_class(tile_ranges[t])] + places[t]] = static_cast<std::uint32_t>(t);
}

}  // namespace

void launch_tile_order(std::uint64_t tiles, const FrameBuffers& b, cudaStream_t stream) {
  if (tiles == 0) return;
  const unsigned blocks = static_cast<unsigned>((tiles + kBlock - 1) / kBlock);
  tile_places_kernel<<<blocks, kBlock, 0, stream>>>(tiles, b.tile_ranges, b.tile_places, b.counters);
  check_cuda(cudaGetLastError(), "tile places kernel launch");
  tile_order_kernel<<<blocks, kBlock, 0, stream>>>(tiles, b.tile_ranges, b.tile_places, b.counters, b.tile_order);
  check_cuda(cudaGetLastError(), "tile order kernel launch");
}

void launch_tile_stats(std::uint64_t tiles, const FrameBuffers& b, cudaStream_t stream) {
  if (tiles == 0) return;
  const unsigned blocks = static_cast<unsigned>((tiles + kBlock - 1) / kBlock);
  tile_max_kernel<<<blocks, kBlock, 0, stream>>>(tiles, b.bins.shift ? b.tile_lists : b.tile_ranges, b.counters);
  check_cuda(cudaGetLastError(), "tile statistics kernel launch");
}

void launch_tile_lists(std::uint64_t pairs, int tiles_x, int tiles_y, const FrameBuffers& b, int which,
                       cudaStream_t stream) {
  const std::uint64_t bins = static_cast<std::uint64_t>(b.bins.x) * static_cast<std::uint64_t>(b.bins.y);
  if (bins == 0) return;
  const BinListArgs args{b.bins,          tiles_x,          tiles_y,      b.tile_ranges, b.values[which],
                         b.tile_values[0], b.tile_values[1], b.tile_lists, b.dense_bins,  b.counters};
  small_bin_lists_kernel<<<static_cast<unsigned>((bins + kListWarps - 1) / kListWarps), kListWarps * kWarp, 0,
                           stream>>>(args);
  check_cuda(cudaGetLastError(), "tile lists kernel launch");
  // At most this many bins hold more than kSmallBin values; the device knows how many do.
  const std::uint64_t most_dense = std::min<std::uint64_t>(bins, pairs / (kSmallBin + 1));
  if (most_dense == 0) return;
  dense_bin_lists_kernel<<<static_cast<unsigned>(most_dense), kListWarps * kWarp, 0, stream>>>(args);
  check_cuda(cudaGetLastError(), "dense tile lists kernel launch");
}

void launch_ranges(std::uint64_t pairs, std::uint64_t bins, const FrameBuffers& b, int which,
                   cudaStream_t stream) {
  check_cuda(cudaMemsetAsync(b.tile_ranges, 0, bins * sizeof(uint2), stream), "bin range reset");
  if (pairs == 0) return;
  const unsigned blocks = static_cast<unsigned>((pairs + kBlock - 1) / kBlock);
  const Records records = frame_records(b, b.bins.shift ? kRecordMask : ~0u);
  if (b.key_format.depth_bits > 0)
    ranges_kernel<<<blocks, kBlock, 0, stream>>>(pairs, reinterpret_cast<const std::uint32_t*>(b.keys[which]),
                                                 b.key_format.depth_bits, b.values[which], records, b.tile_ranges);
  else
    ranges_kernel<<<blocks, kBlock, 0, stream>>>(pairs, b.keys[which], 32, b.values[which], records, b.tile_ranges);
  check_cuda(cudaGetLastError(), "ranges kernel launch");
}

}  // namespace cuda
}  // namespace flashgs
