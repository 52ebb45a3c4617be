// Stage `sort` (CUB radix sort of the pair keys over only the bits the frame needs) and the
// prefix sum of the separate emission path.
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>

#include <algorithm>
#include <climits>
#include <string>

#include "flashgs/error.h"
#include "pipeline.h"

namespace flashgs {
namespace cuda {

std::size_t cub_temp_bytes_needed(std::size_t gaussians, std::uint64_t pairs) {
  std::size_t scan_bytes = 0, sort_bytes = 0;
  check_cuda(cub::DeviceScan::InclusiveSum(nullptr, scan_bytes, static_cast<const std::uint32_t*>(nullptr),
                                           static_cast<std::uint32_t*>(nullptr), static_cast<int>(gaussians)),
             "cub scan size query");
  cub::DoubleBuffer<std::uint64_t> keys(nullptr, nullptr);
  cub::DoubleBuffer<std::uint32_t> compact_keys(nullptr, nullptr);
  cub::DoubleBuffer<std::uint32_t> values(nullptr, nullptr);
  check_cuda(cub::DeviceRadixSort::SortPairs(nullptr, sort_bytes, keys, values, static_cast<int>(pairs), 0, 64),
             "cub sort size query");
  std::size_t compact_bytes = 0;
  check_cuda(cub::DeviceRadixSort::SortPairs(nullptr, compact_bytes, compact_keys, values, static_cast<int>(pairs),
                                             0, 32),
             "cub sort size query");
  return std::max({scan_bytes, sort_bytes, compact_bytes});
}

void launch_scan(std::size_t gaussians, const FrameBuffers& b, cudaStream_t stream) {
  if (gaussians == 0) return;
  std::size_t bytes = b.cub_temp_bytes;
  check_cuda(cub::DeviceScan::InclusiveSum(b.cub_temp, bytes, b.pair_counts, b.pair_offsets,
                                           static_cast<int>(gaussians), stream),
             "cub inclusive scan");
}

namespace {

template <typename KEY>
int sort_pairs(std::uint64_t pairs, int end_bit, const FrameBuffers& b, cudaStream_t stream) {
  cub::DoubleBuffer<KEY> keys(reinterpret_cast<KEY*>(b.keys[0]), reinterpret_cast<KEY*>(b.keys[1]));
  cub::DoubleBuffer<std::uint32_t> values(b.values[0], b.values[1]);
  // No size query per frame: it is host work while the GPU waits for the sort's first launch.
  // The scratch was sized for the pair capacity (cub_temp_bytes_needed), and CUB refuses a
  // scratch too small with an error, which check_cuda reports.
  std::size_t bytes = b.cub_temp_bytes;
  check_cuda(cub::DeviceRadixSort::SortPairs(b.cub_temp, bytes, keys, values, static_cast<int>(pairs), 0, end_bit,
                                             stream),
             "cub radix sort");
  return keys.selector;
}

}  // namespace

int launch_sort(std::uint64_t pairs, int end_bit, const FrameBuffers& b, cudaStream_t stream) {
  if (pairs == 0) return 0;
  if (pairs > static_cast<std::uint64_t>(INT_MAX))
    throw Error("cuda renderer: " + std::to_string(pairs) + " Gaussian-tile pairs exceed the sort's limit");
  if (b.key_format.depth_bits > 0) return sort_pairs<std::uint32_t>(pairs, end_bit, b, stream);
  return sort_pairs<std::uint64_t>(pairs, end_bit, b, stream);
}

}  // namespace cuda
}  // namespace flashgs
