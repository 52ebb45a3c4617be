// Device side of the exact blend order: a pair's order is its Gaussian's exact depth, then its
// id. Both sorts (CUB over the whole frame, ranges.cu; per bin, bin_sort.cu) sort by a key that
// may tie where this order does not (a quantised depth bin, or the same float depth), and put
// each run of equal keys in this order afterwards, so the blend order is exactly the CPU's.
#pragma once

#include <cstdint>

#include "pipeline.h"

namespace flashgs {
namespace cuda {

// The blend records and which Gaussian (scene index) each one is (ids null: record r is Gaussian r).
struct Records {
  const BlendGaussian* gaussians;
  const std::uint32_t* ids;
  std::uint32_t value_mask;  // a pair value's record bits
};

// A frame's records: compact ones name their Gaussian's scene index (record_ids); otherwise
// record r is device Gaussian r, whose scene index is scene_ids[r] (null: r).
inline Records frame_records(const FrameBuffers& b, std::uint32_t value_mask) {
  return Records{b.blend, b.record_ids ? b.record_ids : b.scene_ids, value_mask};
}

// The blend order of a pair: its Gaussian's exact depth bits, then its id.
__device__ __forceinline__ std::uint64_t blend_order(const Records& r, std::uint32_t value) {
  const std::uint32_t record = value & r.value_mask;
  const std::uint32_t id = r.ids ? r.ids[record] : record;
  return (static_cast<std::uint64_t>(__float_as_uint(r.gaussians[record].depth)) << 32) | id;
}

// Sorts a run of pair values in place by blend_order: insertion sort for the usual run of 2-3,
// heap sort for the long runs of a planar scene seen head-on, where insertion would be quadratic.
// `v` may point to global or shared memory.
__device__ inline void sort_run(std::uint32_t* v, unsigned n, const Records& records) {
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

}  // namespace cuda
}  // namespace flashgs
