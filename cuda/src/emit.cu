// Stage `emit`, separate pass (3DGS duplicateWithKeys): after the prefix sum over the pair
// counts, each Gaussian writes its keys at its own offset.
#include "device_common.cuh"
#include "flashgs/gaussian_math.h"
#include "pipeline.h"

namespace flashgs {
namespace cuda {
namespace {

constexpr int kBlock = 256;

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
  for (int ty = f.tile_y0; ty < f.tile_y1 && offset < end; ++ty)
    for (int tx = f.tile_x0; tx < f.tile_x1 && offset < end; ++tx)
      if (!exact || gm::footprint_touches_tile(f, tx, ty, cam.width, cam.height))
        store_pair(buf, offset++, static_cast<unsigned>(ty) * cam.tiles_x + tx, depth_bits,
                   static_cast<std::uint32_t>(i));
}

}  // namespace

void launch_duplicate(std::size_t gaussians, const FrameBuffers& buffers, const gm::CameraParams& camera,
                      bool exact_tile_test, cudaStream_t stream) {
  if (gaussians == 0) return;
  const unsigned blocks = static_cast<unsigned>((gaussians + kBlock - 1) / kBlock);
  duplicate_kernel<<<blocks, kBlock, 0, stream>>>(gaussians, buffers, camera, exact_tile_test);
  check_cuda(cudaGetLastError(), "duplicate kernel launch");
}

}  // namespace cuda
}  // namespace flashgs
