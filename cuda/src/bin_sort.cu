// Stage `sort` of binned frames with compact keys, shaped for the problem: pairs fall into a
// few thousand bins of a few hundred pairs each, so instead of four radix passes over the
// whole frame (CUB: about 12 us each, latency-bound), the pairs are counted per bin (by a
// counting pass, or by emission itself: bin_tally.cuh), a scatter pass puts every pair in its
// bin, and a block per bin sorts the bin by key where it is, in shared memory when it fits.
// The same block then puts runs of equal keys in the exact blend order and writes its four
// tiles' lists, which the ranges pass and the tile-list kernels do on the other paths.
// The order is the CUB path's to the pair (bins by key, ties by sort_order.cuh).
#include <cub/block/block_radix_sort.cuh>

#include <algorithm>
#include <string>

#include "bins.cuh"
#include "device_common.cuh"
#include "flashgs/error.h"
#include "pipeline.h"
#include "sort_order.cuh"

namespace flashgs {
namespace cuda {
namespace {

// The counting and scatter passes: blocks of 256 threads.
constexpr int kPassBlock = 256;
constexpr unsigned kNoBin = 0xffffffffu;

// The per-bin sort: a block of 4 warps. A bin that fits sorts in registers and shared memory
// (CUB's block radix sort, 4 or 8 pairs per thread); a larger one sorts in global memory,
// radix digits of 8 bits. At most 8 pairs per thread keep the kernel at 56 registers, so that
// its blocks displace fewer of the blend's beside them (16 took 80 registers and made the
// frame 10-18 us longer at 4K on the H200, docs/PERFORMANCE.md).
constexpr int kSortWarps = 4;
constexpr int kSortBlock = kSortWarps * kWarp;
constexpr int kSmallItems = 4;
constexpr int kLargeItems = 8;
static_assert(kSortBlock * kLargeItems == static_cast<int>(kBinSortSharedPairsMax), "the largest bin in shared memory");
using SmallBinSort = cub::BlockRadixSort<std::uint32_t, kSortBlock, kSmallItems, std::uint32_t>;
using LargeBinSort = cub::BlockRadixSort<std::uint32_t, kSortBlock, kLargeItems, std::uint32_t>;
constexpr int kDigitBits = 8;
constexpr unsigned kDigits = 1u << kDigitBits;
static_assert(kDigits == 2 * kSortBlock, "each thread scans two digits");
// Loops over a bin load this many words per thread before using any, so that a bin sorted in
// global memory waits for memory once per batch rather than once per word.
constexpr int kBatch = kWarpLoads;

__device__ __forceinline__ unsigned lanes_below() { return (1u << lane_id()) - 1u; }

// Exclusive prefix sum over the block of `value` (all threads call; `warp_totals` holds one
// word per warp). Returns the block's total in `total`.
template <int WARPS>
__device__ __forceinline__ unsigned block_exclusive_sum(unsigned value, unsigned* warp_totals, unsigned& total) {
  const unsigned warp = threadIdx.x / kWarp;
  const unsigned inclusive = warp_inclusive_sum(value);
  if (lane_id() == kWarp - 1) warp_totals[warp] = inclusive;
  __syncthreads();
  unsigned before = 0;
  total = 0;
#pragma unroll
  for (int w = 0; w < WARPS; ++w) {
    if (w == static_cast<int>(warp)) before = total;
    total += warp_totals[w];
  }
  __syncthreads();  // warp_totals may be reused at once
  return before + inclusive - value;
}

// The frame's pairs as the device counted them, or 0 when emission overflowed a capacity: the
// host then grows the buffers and runs the frame again, and this one blends nothing rather
// than reading records that were never written.
__device__ __forceinline__ std::uint64_t frame_pairs(const FrameCounters* counters, std::uint64_t pair_capacity,
                                                     std::uint32_t record_capacity) {
  const std::uint64_t pairs = counters->pairs;
  return pairs > pair_capacity || counters->records > record_capacity ? 0 : pairs;
}

// The block of the counting pass that finishes last turns the counts into each bin's range
// and first free place, and with `order` lists the bins fullest class first for the blend
// (classes by the bit length of the count, as launch_tile_order does for the other paths; the
// order inside a class is immaterial). All threads of every block call this once their counts
// are added.
__device__ void finish_count(unsigned bins, std::uint32_t* fill, uint2* __restrict__ bin_ranges,
                             FrameCounters* counters, std::uint32_t* __restrict__ order) {
  __shared__ bool last;
  __shared__ unsigned warp_totals[kPassBlock / kWarp];
  __shared__ unsigned class_next[kTileClasses];
  __syncthreads();
  if (threadIdx.x == 0) {
    __threadfence();  // cumulative: the block's counts (ordered by the barrier) before the ticket
    last = atomicAdd(&counters->bin_count_blocks, 1u) == gridDim.x - 1;
  }
  __syncthreads();
  if (!last) return;
  __threadfence();
  for (unsigned c = threadIdx.x; c < kTileClasses; c += kPassBlock) class_next[c] = 0;
  __syncthreads();
  constexpr int kScanItems = 8;
  unsigned running = 0;
  for (unsigned base = 0; base < bins; base += kPassBlock * kScanItems) {  // block-uniform
    unsigned count[kScanItems], sum = 0;
#pragma unroll
    for (int k = 0; k < kScanItems; ++k) {
      const unsigned b = base + threadIdx.x * kScanItems + k;
      count[k] = b < bins ? __ldcg(&fill[b]) : 0u;
      sum += count[k];
    }
    unsigned total = 0;
    unsigned start = running + block_exclusive_sum<kPassBlock / kWarp>(sum, warp_totals, total);
#pragma unroll
    for (int k = 0; k < kScanItems; ++k) {
      const unsigned b = base + threadIdx.x * kScanItems + k;
      if (b < bins) {
        bin_ranges[b] = make_uint2(start, start + count[k]);
        fill[b] = start;
        if (order) atomicAdd(&class_next[__clz(count[k])], 1u);
      }
      start += count[k];
    }
    running += total;
  }
  if (!order) return;
  __syncthreads();
  if (threadIdx.x == 0) {  // each class's first place, fullest first
    unsigned first = 0;
    for (int c = 0; c < kTileClasses; ++c) {
      const unsigned n = class_next[c];
      class_next[c] = first;
      first += n;
    }
  }
  __syncthreads();  // and this block's bin_ranges writes are visible to all its threads
  for (unsigned b = threadIdx.x; b < bins; b += kPassBlock) {
    const uint2 range = bin_ranges[b];
    order[atomicAdd(&class_next[__clz(range.y - range.x)], 1u)] = b;
  }
}

// The counting pass and the scatter pass take the pairs in chunks of kChunkPairs.
constexpr int kChunkItems = 8;
constexpr unsigned kChunkPairs = kPassBlock * kChunkItems;

// Thread t's pairs of a chunk: keys, and bins (kNoBin past the frame's pairs).
__device__ __forceinline__ void load_chunk(std::uint64_t chunk, std::uint64_t pairs, const std::uint32_t* __restrict__ keys,
                                           int depth_bits, std::uint32_t (&key)[kChunkItems],
                                           unsigned (&bin)[kChunkItems]) {
  const std::uint64_t first = chunk * kChunkPairs + threadIdx.x;
#pragma unroll
  for (int k = 0; k < kChunkItems; ++k) {
    const std::uint64_t i = first + k * kPassBlock;
    key[k] = i < pairs ? keys[i] : 0u;
    bin[k] = i < pairs ? key[k] >> depth_bits : kNoBin;
  }
}

// The same with the pairs' values (the scatter passes).
__device__ __forceinline__ void load_chunk_pairs(std::uint64_t chunk, std::uint64_t pairs,
                                                 const std::uint32_t* __restrict__ keys,
                                                 const std::uint32_t* __restrict__ values, int depth_bits,
                                                 std::uint32_t (&key)[kChunkItems], std::uint32_t (&value)[kChunkItems],
                                                 unsigned (&bin)[kChunkItems]) {
  load_chunk(chunk, pairs, keys, depth_bits, key, bin);
  const std::uint64_t first = chunk * kChunkPairs + threadIdx.x;
#pragma unroll
  for (int k = 0; k < kChunkItems; ++k) value[k] = bin[k] != kNoBin ? values[first + k * kPassBlock] : 0u;
}

// The counting pass: each block counts its chunks' pairs per bin in shared memory and adds
// them to the bins with one global atomic per bin it met (hot bins serialise atomics per pair).
__global__ void __launch_bounds__(kPassBlock) bin_count_kernel(FrameCounters* counters, std::uint64_t pair_capacity,
                                                               std::uint32_t record_capacity,
                                                               const std::uint32_t* __restrict__ keys, int depth_bits,
                                                               unsigned bins, std::uint32_t* fill,
                                                               uint2* __restrict__ bin_ranges,
                                                               std::uint32_t* __restrict__ order) {
  extern __shared__ unsigned hist[];  // [bins]
  const std::uint64_t pairs = frame_pairs(counters, pair_capacity, record_capacity);
  const std::uint64_t chunks = (pairs + kChunkPairs - 1) / kChunkPairs;
  if (blockIdx.x < chunks) {  // block-uniform
    for (unsigned b = threadIdx.x; b < bins; b += kPassBlock) hist[b] = 0;
    __syncthreads();
    for (std::uint64_t chunk = blockIdx.x; chunk < chunks; chunk += gridDim.x) {
      std::uint32_t key[kChunkItems];
      unsigned bin[kChunkItems];
      load_chunk(chunk, pairs, keys, depth_bits, key, bin);
#pragma unroll
      for (int k = 0; k < kChunkItems; ++k)
        if (bin[k] != kNoBin) atomicAdd(&hist[bin[k]], 1u);
    }
    __syncthreads();
    for (unsigned b = threadIdx.x; b < bins; b += kPassBlock)
      if (hist[b] != 0) atomicAdd(&fill[b], hist[b]);
  }
  finish_count(bins, fill, bin_ranges, counters, order);
}

// The scatter pass: each block takes chunks, counts a chunk's pairs per bin in shared memory,
// reserves its places in each bin with one global atomic and hands them out with shared
// atomics. The order within a bin is whatever the atomics give; the bin sort makes it exact.
// A pair's key and value go out as one 8-byte word: a chunk's pairs land one or two per bin,
// so each store is a memory request of its own, and one per pair halves them.
__global__ void __launch_bounds__(kPassBlock) bin_scatter_kernel(const FrameCounters* counters,
                                                                 std::uint64_t pair_capacity,
                                                                 std::uint32_t record_capacity,
                                                                 const std::uint32_t* __restrict__ keys,
                                                                 const std::uint32_t* __restrict__ values,
                                                                 int depth_bits, unsigned bins, std::uint32_t* fill,
                                                                 uint2* __restrict__ bin_pairs) {
  extern __shared__ unsigned hist[];  // [bins]
  const std::uint64_t pairs = frame_pairs(counters, pair_capacity, record_capacity);
  const std::uint64_t chunks = (pairs + kChunkPairs - 1) / kChunkPairs;
  for (std::uint64_t chunk = blockIdx.x; chunk < chunks; chunk += gridDim.x) {  // block-uniform
    for (unsigned b = threadIdx.x; b < bins; b += kPassBlock) hist[b] = 0;
    std::uint32_t key[kChunkItems], value[kChunkItems];
    unsigned bin[kChunkItems];
    load_chunk_pairs(chunk, pairs, keys, values, depth_bits, key, value, bin);
    __syncthreads();
#pragma unroll
    for (int k = 0; k < kChunkItems; ++k)
      if (bin[k] != kNoBin) atomicAdd(&hist[bin[k]], 1u);
    __syncthreads();
    for (unsigned b = threadIdx.x; b < bins; b += kPassBlock)
      if (hist[b] != 0) hist[b] = atomicAdd(&fill[b], hist[b]);
    __syncthreads();
#pragma unroll
    for (int k = 0; k < kChunkItems; ++k)
      if (bin[k] != kNoBin) {
        bin_pairs[atomicAdd(&hist[bin[k]], 1u)] = make_uint2(key[k], value[k]);
      }
    __syncthreads();  // hist is cleared for the next chunk
  }
}

// A bin's word in bin_scatter_counted_kernel's shared places: each thread of its scan walks a
// run of consecutive bins, and unskewed, a warp's runs would begin on the same bank.
__device__ __forceinline__ unsigned skewed(unsigned bin) { return bin + (bin >> 5); }
constexpr std::size_t counted_scatter_shared_bytes(unsigned bins) {
  return (static_cast<std::size_t>(bins) + bins / 32 + 1) * sizeof(unsigned);
}

// The scatter pass of frames whose emission counted the pairs per bin (bin_tally.cuh): no
// counting pass, and no block that runs after all others to turn the counts into places (a
// chain of loads and barriers on one block that took 6-10 us at 1080p, docs/PERFORMANCE.md).
// Each block scans the counts of every bin itself, block 0 writes the bin ranges,
// and each chunk goes out as in bin_scatter_kernel, its places in a bin reserved with one
// global atomic on the bin's fill (zero at the start).
__global__ void __launch_bounds__(kPassBlock) bin_scatter_counted_kernel(
    const FrameCounters* counters, std::uint64_t pair_capacity, std::uint32_t record_capacity,
    const std::uint32_t* __restrict__ keys, const std::uint32_t* __restrict__ values, int depth_bits, unsigned bins,
    const std::uint32_t* __restrict__ counts, std::uint32_t* fill, uint2* __restrict__ bin_ranges,
    uint2* __restrict__ bin_pairs) {
  extern __shared__ unsigned place[];  // [skewed(bins) + 1]
  __shared__ unsigned warp_totals[kPassBlock / kWarp];
  const std::uint64_t pairs = frame_pairs(counters, pair_capacity, record_capacity);
  if (pairs == 0) {  // block-uniform: nothing stored, or an overflowed frame; every bin empty
    if (blockIdx.x == 0)
      for (unsigned b = threadIdx.x; b < bins; b += kPassBlock) bin_ranges[b] = make_uint2(0u, 0u);
    return;
  }
  // Thread t scans bins [first_bin, end_bin); `start` is its first bin's first place.
  const unsigned per_thread = (bins + kPassBlock - 1) / kPassBlock;
  const unsigned first_bin = min(bins, threadIdx.x * per_thread), end_bin = min(bins, first_bin + per_thread);
  unsigned sum = 0;
  for (unsigned b = first_bin; b < end_bin; ++b) sum += __ldg(counts + b);
  unsigned total = 0;
  const unsigned start = block_exclusive_sum<kPassBlock / kWarp>(sum, warp_totals, total);
  if (blockIdx.x == 0) {
    unsigned at = start;
    for (unsigned b = first_bin; b < end_bin; ++b) {
      const unsigned n = __ldg(counts + b);
      bin_ranges[b] = make_uint2(at, at + n);
      at += n;
    }
  }
  const std::uint64_t chunks = (pairs + kChunkPairs - 1) / kChunkPairs;
  for (std::uint64_t chunk = blockIdx.x; chunk < chunks; chunk += gridDim.x) {  // block-uniform
    for (unsigned b = threadIdx.x; b < bins; b += kPassBlock) place[skewed(b)] = 0;
    std::uint32_t key[kChunkItems], value[kChunkItems];
    unsigned bin[kChunkItems];
    load_chunk_pairs(chunk, pairs, keys, values, depth_bits, key, value, bin);
    __syncthreads();
#pragma unroll
    for (int k = 0; k < kChunkItems; ++k)
      if (bin[k] != kNoBin) atomicAdd(&place[skewed(bin[k])], 1u);
    __syncthreads();
    unsigned at = start;
    for (unsigned b = first_bin; b < end_bin; ++b) {
      const unsigned n = place[skewed(b)];
      if (n != 0) place[skewed(b)] = at + atomicAdd(&fill[b], n);
      at += __ldg(counts + b);
    }
    __syncthreads();
#pragma unroll
    for (int k = 0; k < kChunkItems; ++k)
      if (bin[k] != kNoBin) {
        const unsigned to = atomicAdd(&place[skewed(bin[k])], 1u);
        if (to < total) bin_pairs[to] = make_uint2(key[k], value[k]);  // (counts that disagreed with the pairs)
      }
    __syncthreads();  // the places are cleared for the next chunk
  }
}

// One bin's pairs: keys and values at the same index, in shared or global memory.
struct PairSpan {
  std::uint32_t* keys;
  std::uint32_t* values;
};

// What the bin blocks read and write (FrameBuffers' fields; see launch_bin_blocks).
struct BinSortArgs {
  BinGrid bins;
  int tiles_x, tiles_y;
  const uint2* bin_ranges;
  const uint2* pairs;       // the scatter pass's (key, value) in bin order: keys[1]
  std::uint32_t* keys;      // a bin sorted in global memory: its keys, values[1]
  std::uint32_t* values;    // and values, values[0]
  std::uint32_t* scratch;   // keys[1] as 32-bit words: bin [s, e) may use [2s, 2e) once read
  std::uint32_t* fill;      // the counting passes' per-bin counts, zeroed here for the next frame
  std::uint32_t* counts;    // FrameBuffers::emitted_bin_counts (or null), likewise zeroed here
  std::uint32_t* top_lists;     // tile_values[0]
  std::uint32_t* bottom_lists;  // tile_values[1]
  uint2* tile_lists;
  const std::uint32_t* order;  // block b sorts bin order[b] (null: bin b)
  std::uint32_t* ready;        // ready[bin] = frame_tag once the bin's lists are written (or null)
  std::uint32_t frame_tag;
  Records records;
  unsigned shared_pairs;  // bins of more pairs sort in global memory
};

// The shared memory of a bin-sort block.
struct SortShared {
  union {  // the block sort's scratch, then the sorted bin
    SmallBinSort::TempStorage small;
    LargeBinSort::TempStorage large;
    struct {
      std::uint32_t keys[kBinSortSharedPairsMax];
      std::uint32_t values[kBinSortSharedPairsMax];
    } sorted;
  } bin;
  unsigned counts[kSortWarps][kDigits];  // global-memory sort: per warp and digit a count, then a place
  unsigned warp_totals[kSortWarps];
  unsigned low[kSortWarps], high[kSortWarps];
  unsigned list_counts[kSortWarps][4];
};

__device__ __forceinline__ unsigned digit_of(std::uint32_t key, std::uint32_t low, int shift) {
  return ((key - low) >> shift) & (kDigits - 1);
}

// One stable LSD pass over the digit of (key - low) at `shift`: each warp counts its share per
// digit, a scan turns the counts into places (digit-major, then warp order), and each warp
// places its share in order, 32 pairs at a time.
__device__ void radix_pass(PairSpan from, PairSpan to, unsigned n, std::uint32_t low, int shift, SortShared& sh) {
  const unsigned warp = threadIdx.x / kWarp, lane = lane_id();
  for (unsigned d = threadIdx.x; d < kSortWarps * kDigits; d += kSortBlock) (&sh.counts[0][0])[d] = 0;
  __syncthreads();
  const WarpShare share(n, kSortWarps, threadIdx.x / kWarp);
  for (unsigned first = share.lo; first < share.hi; first += kBatch * kWarp) {  // warp-uniform
    std::uint32_t key[kBatch];
    load_run(from.keys, first, share.hi, key);
#pragma unroll
    for (int g = 0; g < kBatch; ++g) {
      const unsigned d = first + g * kWarp + lane < share.hi ? digit_of(key[g], low, shift) : kDigits;
      const unsigned peers = __match_any_sync(kFullMask, d);
      if (d < kDigits && lane == static_cast<unsigned>(__ffs(peers) - 1)) sh.counts[warp][d] += __popc(peers);
      __syncwarp();  // the next group's leader of a digit may be another lane
    }
  }
  __syncthreads();
  const unsigned d0 = 2 * threadIdx.x, d1 = d0 + 1;
  unsigned total0 = 0, total1 = 0;
#pragma unroll
  for (int w = 0; w < kSortWarps; ++w) {
    total0 += sh.counts[w][d0];
    total1 += sh.counts[w][d1];
  }
  unsigned all = 0;
  unsigned place = block_exclusive_sum<kSortWarps>(total0 + total1, sh.warp_totals, all);
#pragma unroll
  for (int w = 0; w < kSortWarps; ++w) {
    const unsigned c = sh.counts[w][d0];
    sh.counts[w][d0] = place;
    place += c;
  }
#pragma unroll
  for (int w = 0; w < kSortWarps; ++w) {
    const unsigned c = sh.counts[w][d1];
    sh.counts[w][d1] = place;
    place += c;
  }
  __syncthreads();
  for (unsigned first = share.lo; first < share.hi; first += kBatch * kWarp) {  // warp-uniform
    std::uint32_t key[kBatch], value[kBatch];
    load_run(from.keys, first, share.hi, key);
    load_run(from.values, first, share.hi, value);
#pragma unroll
    for (int g = 0; g < kBatch; ++g) {
      const bool real = first + g * kWarp + lane < share.hi;
      const unsigned d = real ? digit_of(key[g], low, shift) : kDigits;
      const unsigned peers = __match_any_sync(kFullMask, d);
      if (real) {
        const unsigned at = sh.counts[warp][d] + __popc(peers & lanes_below());
        to.keys[at] = key[g];
        to.values[at] = value[g];
      }
      __syncwarp();
      if (real && lane == static_cast<unsigned>(__ffs(peers) - 1)) sh.counts[warp][d] += __popc(peers);
      __syncwarp();
    }
  }
  __syncthreads();
}

// Folds this thread's keys into the block's smallest and largest (every thread gets both).
__device__ void block_key_bounds(SortShared& sh, std::uint32_t& low, std::uint32_t& high) {
  low = __reduce_min_sync(kFullMask, low);
  high = __reduce_max_sync(kFullMask, high);
  const unsigned warp = threadIdx.x / kWarp;
  if (lane_id() == 0) {
    sh.low[warp] = low;
    sh.high[warp] = high;
  }
  __syncthreads();
#pragma unroll
  for (int w = 0; w < kSortWarps; ++w) {
    low = min(low, sh.low[w]);
    high = max(high, sh.high[w]);
  }
}

// Copies n pairs (kBatch loads per thread in flight), and the smallest and largest key.
__device__ void copy_pairs(PairSpan from, PairSpan to, unsigned n, std::uint32_t& low, std::uint32_t& high) {
  low = 0xffffffffu;
  high = 0;
  for (unsigned base = 0; base < n; base += kBatch * kSortBlock) {
    std::uint32_t key[kBatch], value[kBatch];
#pragma unroll
    for (int j = 0; j < kBatch; ++j) {
      const unsigned i = base + j * kSortBlock + threadIdx.x;
      key[j] = i < n ? from.keys[i] : 0u;
      value[j] = i < n ? from.values[i] : 0u;
    }
#pragma unroll
    for (int j = 0; j < kBatch; ++j) {
      const unsigned i = base + j * kSortBlock + threadIdx.x;
      if (i < n) {
        to.keys[i] = key[j];
        to.values[i] = value[j];
        low = min(low, key[j]);
        high = max(high, key[j]);
      }
    }
  }
}

// Splits n scattered (key, value) pairs into a span (kBatch loads per thread in flight).
__device__ void split_pairs(const uint2* from, PairSpan to, unsigned n) {
  for (unsigned base = 0; base < n; base += kBatch * kSortBlock) {
    uint2 pair[kBatch];
#pragma unroll
    for (int j = 0; j < kBatch; ++j) {
      const unsigned i = base + j * kSortBlock + threadIdx.x;
      pair[j] = i < n ? from[i] : make_uint2(0u, 0u);
    }
#pragma unroll
    for (int j = 0; j < kBatch; ++j) {
      const unsigned i = base + j * kSortBlock + threadIdx.x;
      if (i < n) {
        to.keys[i] = pair[j].x;
        to.values[i] = pair[j].y;
      }
    }
  }
}

// The smallest and largest key of a span in global memory.
__device__ void span_key_bounds(PairSpan span, unsigned n, std::uint32_t& low, std::uint32_t& high) {
  low = 0xffffffffu;
  high = 0;
  for (unsigned base = 0; base < n; base += kBatch * kSortBlock) {
    std::uint32_t key[kBatch];
#pragma unroll
    for (int j = 0; j < kBatch; ++j) {
      const unsigned i = base + j * kSortBlock + threadIdx.x;
      key[j] = i < n ? span.keys[i] : 0u;
    }
#pragma unroll
    for (int j = 0; j < kBatch; ++j)
      if (base + j * kSortBlock + threadIdx.x < n) {
        low = min(low, key[j]);
        high = max(high, key[j]);
      }
  }
}

// Runs of equal keys (equal depth bins) in the exact blend order.
__device__ void order_ties(PairSpan span, unsigned n, const Records& records) {
  for (unsigned base = 0; base < n; base += kBatch * kSortBlock) {
    bool run_start[kBatch];  // all loads of the batch before any run is sorted
#pragma unroll
    for (int j = 0; j < kBatch; ++j) {
      const unsigned i = base + j * kSortBlock + threadIdx.x;
      run_start[j] = i + 1 < n && span.keys[i + 1] == span.keys[i] && (i == 0 || span.keys[i - 1] != span.keys[i]);
    }
#pragma unroll
    for (int j = 0; j < kBatch; ++j) {
      if (!run_start[j]) continue;
      const unsigned i = base + j * kSortBlock + threadIdx.x;
      unsigned end = i + 2;
      while (end < n && span.keys[end] == span.keys[i]) ++end;
      sort_run(span.values + i, end - i, records);
    }
  }
  __syncthreads();
}

// The bin's four tile lists from its sorted values.
__device__ void write_tile_lists(const BinSortArgs& a, unsigned bin, const std::uint32_t* values, const BinLists& lists,
                                 SortShared& sh) {
  unsigned total[4];
  write_bin_lists<kSortWarps>(values, lists, sh.list_counts, total);
  record_tile_list(a.bins, a.tiles_x, a.tiles_y, a.tile_lists, bin, lists, total, threadIdx.x);
}

// Sorts a bin of at most kSortBlock * ITEMS pairs by (key - low) in registers (CUB), and
// leaves it in sh.bin.sorted, the keys relative to the bin's smallest. The input order is
// immaterial (ties are put in the exact order afterwards); so that padding sorts last, it gets
// a key one bit above every real one.
template <typename BlockSort, int ITEMS>
__device__ void sort_in_shared(const uint2* pairs, unsigned n, BlockSort sorter, SortShared& sh) {
  std::uint32_t key[ITEMS], value[ITEMS];
  std::uint32_t low = 0xffffffffu, high = 0;
#pragma unroll
  for (int j = 0; j < ITEMS; ++j) {
    const unsigned i = j * kSortBlock + threadIdx.x;
    const uint2 pair = i < n ? pairs[i] : make_uint2(0u, 0u);
    key[j] = pair.x;
    value[j] = pair.y;
    if (i < n) {
      low = min(low, key[j]);
      high = max(high, key[j]);
    }
  }
  block_key_bounds(sh, low, high);
  const int bits = low == high ? 0 : 32 - __clz(high - low);  // at most 31: bins take a key bit
#pragma unroll
  for (int j = 0; j < ITEMS; ++j) key[j] = j * kSortBlock + threadIdx.x < n ? key[j] - low : 1u << bits;
  sorter.Sort(key, value, 0, bits + 1);
  __syncthreads();  // the scratch becomes the sorted bin
#pragma unroll
  for (int j = 0; j < ITEMS; ++j) {
    const unsigned place = threadIdx.x * ITEMS + j;  // blocked: thread t holds places t * ITEMS + j
    if (place < n) {
      sh.bin.sorted.keys[place] = key[j];
      sh.bin.sorted.values[place] = value[j];
    }
  }
  __syncthreads();
}

// Sorts a bin too large for shared memory where it lies, in 8-bit radix passes through its
// scratch, and leaves it back home.
__device__ void sort_in_global(PairSpan home, PairSpan scratch, unsigned n, SortShared& sh) {
  std::uint32_t low, high;
  span_key_bounds(home, n, low, high);
  block_key_bounds(sh, low, high);
  const int bits = low == high ? 0 : 32 - __clz(high - low);
  PairSpan from = home, to = scratch;
  for (int shift = 0; shift < bits; shift += kDigitBits) {
    radix_pass(from, to, n, low, shift, sh);
    const PairSpan t = from;
    from = to;
    to = t;
  }
  if (from.keys != home.keys) {  // the scratch is where the bin's bottom lists go
    copy_pairs(from, home, n, low, high);
    __syncthreads();
  }
}

// Tells a blend block waiting on `bin` that its lists are written (every thread calls, after
// its last write of them).
__device__ __forceinline__ void publish_bin(const BinSortArgs& a, unsigned bin) {
  if (!a.ready) return;
  __threadfence();
  __syncthreads();
  if (threadIdx.x == 0) store_release(a.ready + bin, a.frame_tag);
}

// A block per bin: sort by key (the bin's keys differ only in their depth bins, and only the
// bits in which the bin's keys differ are sorted), order the ties, write the lists.
__global__ void __launch_bounds__(kSortBlock) bin_sort_kernel(BinSortArgs a) {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
  // The blend may be scheduled once every bin block has started: a blend block then waits only
  // for a bin block that is running, so the wait always ends.
  asm volatile("griddepcontrol.launch_dependents;");
#endif
  __shared__ SortShared sh;
  const unsigned bin = a.order ? a.order[blockIdx.x] : blockIdx.x;
  if (threadIdx.x == 0) {  // the scatter pass was their last user this frame
    a.fill[bin] = 0;
    if (a.counts) a.counts[bin] = 0;
  }
  const uint2 range = a.bin_ranges[bin];
  const unsigned n = range.y - range.x;
  const BinLists lists{a.top_lists, a.bottom_lists, range.x, n};
  if (n == 0) {  // whole block
    const unsigned none[4] = {0, 0, 0, 0};
    record_tile_list(a.bins, a.tiles_x, a.tiles_y, a.tile_lists, bin, lists, none, threadIdx.x);
    publish_bin(a, bin);
    return;
  }
  const uint2* pairs = a.pairs + range.x;
  const PairSpan home{a.keys + range.x, a.values + range.x};
  PairSpan sorted = home;
  if (n <= a.shared_pairs) {
    sorted = PairSpan{sh.bin.sorted.keys, sh.bin.sorted.values};
    if (n <= kSortBlock * kSmallItems) sort_in_shared<SmallBinSort, kSmallItems>(pairs, n, SmallBinSort(sh.bin.small), sh);
    else sort_in_shared<LargeBinSort, kLargeItems>(pairs, n, LargeBinSort(sh.bin.large), sh);
  } else {
    split_pairs(pairs, home, n);
    __syncthreads();  // the pairs' words become the radix passes' scratch
    sort_in_global(home, PairSpan{a.scratch + 2ull * range.x, a.scratch + 2ull * range.x + n}, n, sh);
  }
  order_ties(sorted, n, a.records);
  write_tile_lists(a, bin, sorted.values, lists, sh);
  publish_bin(a, bin);
}

}  // namespace

// Grids of the counting and scatter passes, sized on the host before the pair count is known:
// the scatter pass takes a 4K frame's chunks one per block; a counting block takes several
// chunks, so that fewer blocks add their counts to every bin.
constexpr unsigned kScatterBlocks = 2048;
constexpr unsigned kCountBlocks = 512;

void launch_bin_pairs(const FrameBuffers& b, std::uint32_t* order, cudaStream_t stream) {
  const unsigned bins = static_cast<unsigned>(b.bins.x) * static_cast<unsigned>(b.bins.y);
  if (bins == 0) return;
  if (bins > kBinSortMaxBins)
    throw Error("cuda renderer: internal error, a bin sort of " + std::to_string(bins) + " bins (at most " +
                std::to_string(kBinSortMaxBins) + ")");
  const std::uint64_t most_chunks = std::max<std::uint64_t>(1, (b.pair_capacity + kChunkPairs - 1) / kChunkPairs);
  const std::size_t hist_bytes = bins * sizeof(unsigned);
  const std::uint32_t* keys = reinterpret_cast<const std::uint32_t*>(b.keys[0]);
  const int depth_bits = b.key_format.depth_bits;
  if (b.emitted_bin_counts) {
    if (order) throw Error("cuda renderer: internal error, a bin order asked of counts the emission took");
    static const bool allowed = [] {
      check_cuda(cudaFuncSetAttribute(bin_scatter_counted_kernel, cudaFuncAttributeMaxDynamicSharedMemorySize,
                                      static_cast<int>(counted_scatter_shared_bytes(kBinSortMaxBins))),
                 "bin scatter shared memory");
      return true;
    }();
    (void)allowed;
    bin_scatter_counted_kernel<<<static_cast<unsigned>(std::min<std::uint64_t>(kScatterBlocks, most_chunks)),
                                 kPassBlock, counted_scatter_shared_bytes(bins), stream>>>(
        b.counters, b.pair_capacity, b.record_capacity, keys, b.pair_values, depth_bits, bins, b.emitted_bin_counts,
        b.bin_fill, b.tile_ranges, reinterpret_cast<uint2*>(b.keys[1]));
    check_cuda(cudaGetLastError(), "bin scatter kernel launch");
    return;
  }
  bin_count_kernel<<<static_cast<unsigned>(std::min<std::uint64_t>(kCountBlocks, most_chunks)), kPassBlock, hist_bytes,
                     stream>>>(b.counters, b.pair_capacity, b.record_capacity, keys, depth_bits, bins, b.bin_fill,
                               b.tile_ranges, order);
  check_cuda(cudaGetLastError(), "bin count kernel launch");
  bin_scatter_kernel<<<static_cast<unsigned>(std::min<std::uint64_t>(kScatterBlocks, most_chunks)), kPassBlock,
                       hist_bytes, stream>>>(b.counters, b.pair_capacity, b.record_capacity, keys, b.pair_values,
                                             depth_bits, bins, b.bin_fill, reinterpret_cast<uint2*>(b.keys[1]));
  check_cuda(cudaGetLastError(), "bin scatter kernel launch");
}

void launch_bin_blocks(int tiles_x, int tiles_y, const FrameBuffers& b, unsigned shared_pairs,
                       const std::uint32_t* order, std::uint32_t* ready, std::uint32_t frame_tag, cudaStream_t stream) {
  const unsigned bins = static_cast<unsigned>(b.bins.x) * static_cast<unsigned>(b.bins.y);
  if (bins == 0) return;
  BinSortArgs args{};
  args.bins = b.bins;
  args.tiles_x = tiles_x;
  args.tiles_y = tiles_y;
  args.bin_ranges = b.tile_ranges;
  args.pairs = reinterpret_cast<const uint2*>(b.keys[1]);
  args.keys = b.values[1];
  args.values = b.values[0];
  args.scratch = reinterpret_cast<std::uint32_t*>(b.keys[1]);
  args.fill = b.bin_fill;
  args.counts = b.emitted_bin_counts;
  args.top_lists = b.tile_values[0];
  args.bottom_lists = b.tile_values[1];
  args.tile_lists = b.tile_lists;
  args.order = order;
  args.ready = ready;
  args.frame_tag = frame_tag;
  args.records = frame_records(b, kRecordMask);
  args.shared_pairs = std::min(shared_pairs, kBinSortSharedPairsMax);
  bin_sort_kernel<<<bins, kSortBlock, 0, stream>>>(args);
  check_cuda(cudaGetLastError(), "bin sort kernel launch");
}

}  // namespace cuda
}  // namespace flashgs
