// Stage `emit`, separate pass (3DGS duplicateWithKeys): after the prefix sum over the pair
// counts, each Gaussian writes its keys (one per bin it touches) at its own offset.
#include "bins.cuh"
#include "device_common.cuh"
#include "flashgs/gaussian_math.h"
#include "pipeline.h"

namespace flashgs {
namespace cuda {
namespace {

constexpr int kBlock = 256;

// SHIFT is buf.bins.shift as a constant: with the shift read at run time the bin loops keep
// both bin sizes' code live (57 registers against 40), which halved this pass's speed.
template <int SHIFT>
__global__ void __launch_bounds__(kBlock) duplicate_kernel(std::size_t gaussians, FrameBuffers buf,
                                                           gm::CameraParams cam, bool exact) {
  const std::size_t i = static_cast<std::size_t>(blockIdx.x) * kBlock + threadIdx.x;
  if (i >= gaussians) return;
  const unsigned count = buf.pair_counts[i];
  if (count == 0) return;
  const gm::Footprint f = buf.footprints[i];
  const std::uint32_t depth_bits = sort_depth(buf.key_format, f.depth);
  unsigned long long offset = buf.pair_offsets[i] - count;
  const unsigned long long end = offset + count;
  const BinBox bins(f, SHIFT);
  for (int by = bins.y0; by < bins.y1 && offset < end; ++by)
    for (int bx = bins.x0; bx < bins.x1 && offset < end; ++bx) {
      const unsigned tiles = footprint_bin_tiles(f, SHIFT, bx, by, cam, exact);
      if (tiles)
        store_pair(buf, offset++, static_cast<unsigned>(by) * buf.bins.x + bx, depth_bits,
                   pair_value(buf.bins, static_cast<std::uint32_t>(i), tiles));
    }
}

}  // namespace

void launch_duplicate(std::size_t gaussians, const FrameBuffers& buffers, const gm::CameraParams& camera,
                      bool exact_tile_test, cudaStream_t stream) {
  if (gaussians == 0) return;
  const unsigned blocks = static_cast<unsigned>((gaussians + kBlock - 1) / kBlock);
  static_assert(kMacroBinShift == 1, "one instance per bin size");
  if (buffers.bins.shift == kMacroBinShift)
    duplicate_kernel<kMacroBinShift><<<blocks, kBlock, 0, stream>>>(gaussians, buffers, camera, exact_tile_test);
  else
    duplicate_kernel<0><<<blocks, kBlock, 0, stream>>>(gaussians, buffers, camera, exact_tile_test);
  check_cuda(cudaGetLastError(), "duplicate kernel launch");
}

}  // namespace cuda
}  // namespace flashgs
