// Stage `sort` of the tile-sort path: the pairs counted per tile during emission become one
// bin per tile (offsets from a scan of the counts, then a scatter); the blend depth-sorts each
// bin in shared memory. Instead of radix passes over every pair, each pair is moved once.
#include <cub/block/block_reduce.cuh>
#include <cub/block/block_scan.cuh>

#include "device_common.cuh"
#include "pipeline.h"

namespace flashgs {
namespace cuda {
namespace {

constexpr int kScanThreads = 1024;
constexpr int kScatterBlock = 256;

// One block: each thread sums a run of consecutive tiles, a block scan gives the run's
// offset, and the thread writes its tiles' starts. Tiles are at most ~10^5 (an 8K frame has
// 137k), so one block is faster than a device-wide scan's several launches.
__global__ void __launch_bounds__(kScanThreads) bin_offsets_kernel(std::uint64_t tiles,
                                                                   const std::uint32_t* __restrict__ counts,
                                                                   uint2* __restrict__ tile_ranges,
                                                                   FrameCounters* counters) {
  using Scan = cub::BlockScan<unsigned, kScanThreads>;
  using Reduce = cub::BlockReduce<unsigned, kScanThreads>;
  __shared__ union {
    typename Scan::TempStorage scan;
    typename Reduce::TempStorage reduce;
  } temp;
  const std::uint64_t run = (tiles + kScanThreads - 1) / kScanThreads;
  const std::uint64_t first = threadIdx.x * run;
  const std::uint64_t last = first + run < tiles ? first + run : tiles;
  unsigned sum = 0, fullest = 0;
  for (std::uint64_t t = first; t < last; ++t) {
    const unsigned c = counts[t];
    sum += c;
    fullest = c > fullest ? c : fullest;
  }
  unsigned offset = 0;
  Scan(temp.scan).ExclusiveSum(sum, offset);
  __syncthreads();  // temp is reused by the reduction
  const unsigned block_max = Reduce(temp.reduce).Reduce(fullest, [](unsigned x, unsigned y) { return x > y ? x : y; });
  if (threadIdx.x == 0) counters->max_tile_pairs = block_max;
  for (std::uint64_t t = first; t < last; ++t) {
    tile_ranges[t] = make_uint2(offset, offset);
    offset += counts[t];
  }
}

// KEY: std::uint64_t (tile << 32 | depth bits) or std::uint32_t (tile << depth_bits | bin:
// the exact depth is then read from the Gaussian's blend record).
template <typename KEY>
__global__ void __launch_bounds__(kScatterBlock) bin_scatter_kernel(std::uint64_t pairs, const KEY* __restrict__ keys,
                                                                    int tile_shift,
                                                                    const std::uint32_t* __restrict__ values,
                                                                    const BlendGaussian* __restrict__ gaussians,
                                                                    uint2* tile_ranges,
                                                                    std::uint64_t* __restrict__ bins) {
  const std::uint64_t i = static_cast<std::uint64_t>(blockIdx.x) * kScatterBlock + threadIdx.x;
  if (i >= pairs) return;
  const KEY key = keys[i];
  const std::uint32_t id = values[i];
  const std::uint32_t tile = static_cast<std::uint32_t>(key >> tile_shift);
  const std::uint32_t depth = sizeof(KEY) == 8 ? static_cast<std::uint32_t>(key) : __float_as_uint(gaussians[id].depth);
  const unsigned slot = atomicAdd(&tile_ranges[tile].y, 1u);
  bins[slot] = (static_cast<std::uint64_t>(depth) << 32) | id;
}

}  // namespace

void launch_bin_offsets(std::uint64_t tiles, const FrameBuffers& b, cudaStream_t stream) {
  if (tiles == 0) return;
  bin_offsets_kernel<<<1, kScanThreads, 0, stream>>>(tiles, b.tile_counts, b.tile_ranges, b.counters);
  check_cuda(cudaGetLastError(), "bin offsets kernel launch");
}

void launch_bin_scatter(std::uint64_t pairs, const FrameBuffers& b, cudaStream_t stream) {
  if (pairs == 0) return;
  const unsigned blocks = static_cast<unsigned>((pairs + kScatterBlock - 1) / kScatterBlock);
  if (b.key_format.depth_bits > 0)
    bin_scatter_kernel<<<blocks, kScatterBlock, 0, stream>>>(pairs, reinterpret_cast<const std::uint32_t*>(b.keys[0]),
                                                             b.key_format.depth_bits, b.values[0], b.blend,
                                                             b.tile_ranges, b.keys[1]);
  else
    bin_scatter_kernel<<<blocks, kScatterBlock, 0, stream>>>(pairs, b.keys[0], 32, b.values[0], b.blend,
                                                             b.tile_ranges, b.keys[1]);
  check_cuda(cudaGetLastError(), "bin scatter kernel launch");
}

}  // namespace cuda
}  // namespace flashgs
