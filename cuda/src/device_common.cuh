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

// A flag between blocks of kernels that run at once (the bin blocks and the blend): the
// release makes the block's earlier writes visible to whoever acquires the value.
__device__ __forceinline__ void store_release(std::uint32_t* flag, std::uint32_t value) {
  asm volatile("st.release.gpu.global.u32 [%0], %1;" ::"l"(flag), "r"(value) : "memory");
}
__device__ __forceinline__ std::uint32_t load_acquire(const std::uint32_t* flag) {
  std::uint32_t value;
  asm volatile("ld.acquire.gpu.global.u32 %0, [%1];" : "=r"(value) : "l"(flag) : "memory");
  return value;
}

// Words a lane loads at once when a warp walks an array (all in flight before any is used).
constexpr int kWarpLoads = 8;
constexpr unsigned kWarpRun = kWarp * kWarpLoads;

// The run of words from `first` (up to `end`; words there and beyond read as 0): lane l gets
// first + k * 32 + l in word[k].
__device__ __forceinline__ void load_run(const std::uint32_t* src, unsigned first, unsigned end,
                                         std::uint32_t (&word)[kWarpLoads]) {
#pragma unroll
  for (int k = 0; k < kWarpLoads; ++k) {
    const unsigned i = first + k * kWarp + lane_id();
    word[k] = i < end ? src[i] : 0u;
  }
}

// Warp `warp` of `warps`' share of n items: [lo, hi), consecutive, so that walking the shares
// in warp order walks the items in order.
struct WarpShare {
  unsigned lo, hi;
  __device__ WarpShare(unsigned n, unsigned warps, unsigned warp) {
    const unsigned per = (n + warps - 1) / warps;
    lo = min(n, warp * per);
    hi = min(n, lo + per);
  }
};

// The depth part of a Gaussian's sort keys in format k (see KeyFormat): the float's bits
// (positive floats order like their bit patterns), or its clamped bin.
__device__ __forceinline__ std::uint32_t sort_depth(const KeyFormat& k, float depth) {
  const std::uint32_t bits = __float_as_uint(depth);
  if (k.depth_bits == 0) return bits;
  const long long bin = static_cast<long long>(bits >> (23 - k.mantissa_bits)) -
                        (static_cast<long long>(k.exponent_base) << k.mantissa_bits);
  const long long last = (1ll << k.depth_bits) - 1;
  return static_cast<std::uint32_t>(bin < 0 ? 0 : (bin > last ? last : bin));
}

// Stores one pair if it fits: an offset at or past the capacity writes nothing; the host
// sees the wanted total in FrameCounters::pairs, grows the buffers and runs the frame again.
// `bin` indexes FrameBuffers::bins, `value` is the pair's (bins.cuh, pair_value).
__device__ __forceinline__ void store_pair(const FrameBuffers& b, unsigned long long offset, std::uint32_t bin,
                                           std::uint32_t depth, std::uint32_t value) {
  if (offset < b.pair_capacity) {
    if (b.key_format.depth_bits > 0)
      reinterpret_cast<std::uint32_t*>(b.keys[0])[offset] = (bin << b.key_format.depth_bits) | depth;
    else
      b.keys[0][offset] = (static_cast<std::uint64_t>(bin) << 32) | depth;
    b.pair_values[offset] = value;
  }
}

}  // namespace cuda
}  // namespace flashgs
