// Stage `ranges`: each tile's [start, end) in the sorted pairs, and runs of equal
// (tile, depth) keys put in Gaussian-id order so the blend order is exactly the CPU's.
#include "device_common.cuh"
#include "pipeline.h"

namespace flashgs {
namespace cuda {
namespace {

constexpr int kBlock = 256;

// Heap sort of a short array in place: a run of equal keys is normally 2 long, but a planar
// scene seen head-on can give thousands, where insertion sort would be quadratic.
__device__ void sort_run(std::uint32_t* v, unsigned n) {
  if (n <= 16) {
    for (unsigned a = 1; a < n; ++a) {
      const std::uint32_t x = v[a];
      unsigned b = a;
      for (; b > 0 && v[b - 1] > x; --b) v[b] = v[b - 1];
      v[b] = x;
    }
    return;
  }
  auto sift = [v](unsigned root, unsigned size) {
    for (;;) {
      unsigned child = 2 * root + 1;
      if (child >= size) return;
      if (child + 1 < size && v[child + 1] > v[child]) ++child;
      if (v[root] >= v[child]) return;
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

__global__ void __launch_bounds__(kBlock) ranges_kernel(std::uint64_t pairs, const std::uint64_t* __restrict__ keys,
                                                        std::uint32_t* __restrict__ values, uint2* tile_ranges) {
  const std::uint64_t i = static_cast<std::uint64_t>(blockIdx.x) * kBlock + threadIdx.x;
  if (i >= pairs) return;
  const std::uint64_t key = keys[i];
  const std::uint32_t tile = static_cast<std::uint32_t>(key >> 32);
  const bool run_start = i == 0 || keys[i - 1] != key;
  if (i == 0 || static_cast<std::uint32_t>(keys[i - 1] >> 32) != tile) tile_ranges[tile].x = static_cast<unsigned>(i);
  if (i + 1 == pairs || static_cast<std::uint32_t>(keys[i + 1] >> 32) != tile)
    tile_ranges[tile].y = static_cast<unsigned>(i + 1);
  // Atomics made the emission order, hence the order of equal keys, vary from run to run.
  if (run_start && i + 1 < pairs && keys[i + 1] == key) {
    std::uint64_t end = i + 2;
    while (end < pairs && keys[end] == key) ++end;
    sort_run(values + i, static_cast<unsigned>(end - i));
  }
}

}  // namespace

void launch_ranges(std::uint64_t pairs, std::uint64_t tiles, const std::uint64_t* keys, std::uint32_t* values,
                   uint2* tile_ranges, cudaStream_t stream) {
  check_cuda(cudaMemsetAsync(tile_ranges, 0, tiles * sizeof(uint2), stream), "tile range reset");
  if (pairs == 0) return;
  const unsigned blocks = static_cast<unsigned>((pairs + kBlock - 1) / kBlock);
  ranges_kernel<<<blocks, kBlock, 0, stream>>>(pairs, keys, values, tile_ranges);
  check_cuda(cudaGetLastError(), "ranges kernel launch");
}

}  // namespace cuda
}  // namespace flashgs
