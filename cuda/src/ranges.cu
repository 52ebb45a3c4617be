// Stage `ranges`: each bin's [start, end) in the sorted pairs, the blend's bin order (fullest
// first), and runs of equal keys put in (depth, Gaussian id) order, so the blend order is
// exactly the CPU's whatever the key format: equal 64-bit keys share their depth (the atomics
// of emission shuffled their records), equal compact keys share a quantised depth bin. (A
// bin is a tile, or 2x2 tiles with macro bins: pipeline.h, BinGrid.)
#include "device_common.cuh"
#include "pipeline.h"

namespace flashgs {
namespace cuda {
namespace {

constexpr int kBlock = 256;

// The blend records and which Gaussian each one is (ids null: record r is Gaussian r).
struct Records {
  const BlendGaussian* gaussians;
  const std::uint32_t* ids;
  std::uint32_t value_mask;  // a pair value's record bits
};

// The blend order of a pair: its Gaussian's exact depth bits, then its id.
__device__ __forceinline__ std::uint64_t blend_order(const Records& r, std::uint32_t value) {
  const std::uint32_t record = value & r.value_mask;
  const std::uint32_t id = r.ids ? r.ids[record] : record;
  return (static_cast<std::uint64_t>(__float_as_uint(r.gaussians[record].depth)) << 32) | id;
}

// Sorts a run of records in place by blend_order: insertion sort for the usual run of 2-3,
// heap sort for the long runs of a planar scene seen head-on, where insertion would be quadratic.
__device__ void sort_run(std::uint32_t* v, unsigned n, const Records& records) {
  if (n <= 16) {
    for (unsigned a = 1; a < n; ++a) {
      const std::uint32_t x = v[a];
      const std::uint64_t key = blend_order(records, x);
      unsigned b = a;
      for (; b > 0 && blend_order(records, v[b - 1]) > key; --b) v[b] = v[b - 1];
      v[b] = x;
    }
    return;
  }
  auto sift = [v, records](unsigned root, unsigned size) {
    for (;;) {
      unsigned child = 2 * root + 1;
      if (child >= size) return;
      if (child + 1 < size && blend_order(records, v[child + 1]) > blend_order(records, v[child])) ++child;
      if (blend_order(records, v[root]) >= blend_order(records, v[child])) return;
      const std::uint32_t t = v[root];
      v[root] = v[child];
      v[child] = t;
      root = child;
    }
  };
  for (unsigned r = n / 2; r-- > 0;) sift(r, n);
  for (unsigned end = n - 1; end > 0; --end) {
    const std::uint32_t t = v[0];
    v[0] = v[end];
    v[end] = t;
    sift(0, end);
  }
}

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
    atomicMax(&counters->max_tile_pairs, warp_max);
    atomicAdd(&counters->tile_pairs, static_cast<unsigned long long>(warp_sum));
  }
}

// Binned frames: each tile's pairs (the values of its bin that carry its bit), their sum and
// the largest, and counts[tile] unless counts is null. A warp per tile.
__global__ void __launch_bounds__(kBlock) binned_tile_stats_kernel(int tiles_x, int tiles_y, BinGrid bins,
                                                                   const uint2* __restrict__ bin_ranges,
                                                                   const std::uint32_t* __restrict__ values,
                                                                   std::uint32_t* counts, FrameCounters* counters) {
  const std::uint64_t t = (static_cast<std::uint64_t>(blockIdx.x) * kBlock + threadIdx.x) / kWarp;
  if (t >= static_cast<std::uint64_t>(tiles_x) * static_cast<std::uint64_t>(tiles_y)) return;  // whole warp
  const int tx = static_cast<int>(t % static_cast<unsigned>(tiles_x)), ty = static_cast<int>(t / static_cast<unsigned>(tiles_x));
  const int side = 1 << bins.shift;
  const uint2 range = bin_ranges[(ty >> bins.shift) * bins.x + (tx >> bins.shift)];
  const std::uint32_t bit = 1u << (((ty & (side - 1)) << bins.shift) + (tx & (side - 1)) + kBinTileBitsShift);
  unsigned n = 0;
  for (unsigned i = range.x + lane_id(); i < range.y; i += kWarp) n += (values[i] & bit) ? 1u : 0u;
  n = __reduce_add_sync(kFullMask, n);
  if (lane_id() == 0) {
    if (counts) counts[t] = n;
    if (n > 0) {
      atomicMax(&counters->max_tile_pairs, n);
      atomicAdd(&counters->tile_pairs, static_cast<unsigned long long>(n));
    }
  }
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

void launch_tile_stats(int tiles_x, int tiles_y, const FrameBuffers& b, int which, std::uint32_t* counts,
                       cudaStream_t stream) {
  const std::uint64_t tiles = static_cast<std::uint64_t>(tiles_x) * static_cast<std::uint64_t>(tiles_y);
  if (tiles == 0) return;
  if (b.bins.shift == 0) {
    const unsigned blocks = static_cast<unsigned>((tiles + kBlock - 1) / kBlock);
    tile_max_kernel<<<blocks, kBlock, 0, stream>>>(tiles, b.tile_ranges, b.counters);
  } else {
    const unsigned blocks = static_cast<unsigned>((tiles * kWarp + kBlock - 1) / kBlock);
    binned_tile_stats_kernel<<<blocks, kBlock, 0, stream>>>(tiles_x, tiles_y, b.bins, b.tile_ranges, b.values[which],
                                                            counts, b.counters);
  }
  check_cuda(cudaGetLastError(), "tile statistics kernel launch");
}

void launch_ranges(std::uint64_t pairs, std::uint64_t bins, const FrameBuffers& b, int which,
                   cudaStream_t stream) {
  check_cuda(cudaMemsetAsync(b.tile_ranges, 0, bins * sizeof(uint2), stream), "bin range reset");
  if (pairs == 0) return;
  const unsigned blocks = static_cast<unsigned>((pairs + kBlock - 1) / kBlock);
  const Records records{b.blend, b.record_ids, b.bins.shift ? kRecordMask : ~0u};
  if (b.key_format.depth_bits > 0)
    ranges_kernel<<<blocks, kBlock, 0, stream>>>(pairs, reinterpret_cast<const std::uint32_t*>(b.keys[which]),
                                                 b.key_format.depth_bits, b.values[which], records, b.tile_ranges);
  else
    ranges_kernel<<<blocks, kBlock, 0, stream>>>(pairs, b.keys[which], 32, b.values[which], records, b.tile_ranges);
  check_cuda(cudaGetLastError(), "ranges kernel launch");
}

}  // namespace cuda
}  // namespace flashgs
