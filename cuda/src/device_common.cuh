// Device-only helpers shared by the stage kernels: warp scans and reductions, key packing.
#pragma once

#include <cstdint>

#include "pipeline.h"

namespace flashgs {
namespace cuda {

constexpr unsigned kFullMask = 0xffffffffu;

__device__ __forceinline__ unsigned lane_id() { return threadIdx.x & (kWarp - 1); }

// Inclusive prefix sum over the 32 lanes (all lanes must call).
__device__ __forceinline__ unsigned warp_inclusive_sum(unsigned v) {
  const unsigned lane = lane_id();
#pragma unroll
  for (int offset = 1; offset < kWarp; offset <<= 1) {
    const unsigned other = __shfl_up_sync(kFullMask, v, offset);
    if (lane >= static_cast<unsigned>(offset)) v += other;
  }
  return v;
}

// The 64-bit sort key: tile in the high word, the depth's float bits (positive, so they
// order like the depths) in the low word.
__device__ __forceinline__ std::uint64_t make_key(std::uint32_t tile, std::uint32_t depth_bits) {
  return (static_cast<std::uint64_t>(tile) << 32) | depth_bits;
}

// Stores one pair if it fits: an offset at or past the capacity writes nothing; the host
// sees the wanted total in FrameCounters::pairs, grows the buffers and runs the frame again.
__device__ __forceinline__ void store_pair(const FrameBuffers& b, unsigned long long offset, std::uint32_t tile,
                                           std::uint32_t depth_bits, std::uint32_t gaussian) {
  if (offset < b.pair_capacity) {
    b.keys[0][offset] = make_key(tile, depth_bits);
    b.values[0][offset] = gaussian;
  }
}

}  // namespace cuda
}  // namespace flashgs
