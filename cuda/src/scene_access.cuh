// A Gaussian's shape as DeviceScene holds it, in either layout: floats, or (fp16_shape) the
// rotation, scale and opacity as halves. The conversion from half to float is exact, so the
// values are those the CPU backend rounds to (gm::round_to_half) bit for bit.
#pragma once

#include <cuda_fp16.h>

#include "pipeline.h"

namespace flashgs {
namespace cuda {

struct GaussianShape {
  float position[3];
  float opacity;
  float quaternion[4];  // w, x, y, z
  float scale[3];
  float dc_red;         // SH DC red (stored beside the shape in both layouts)
};

__device__ __forceinline__ float low_half(unsigned word) {
  return __half2float(__ushort_as_half(static_cast<unsigned short>(word & 0xffffu)));
}
__device__ __forceinline__ float high_half(unsigned word) {
  return __half2float(__ushort_as_half(static_cast<unsigned short>(word >> 16)));
}

// Position (x, y, z) and opacity (w): all that culling by the centre reads.
__device__ __forceinline__ float4 load_position_opacity(const DeviceScene& scene, std::size_t i) {
  if (!scene.shape_half) return __ldg(scene.position_opacity + i);
  const float4 p = __ldg(scene.position_dc_r + i);
  return make_float4(p.x, p.y, p.z, high_half(__ldg(&scene.shape_record[i].w)));
}

__device__ __forceinline__ GaussianShape load_shape(const DeviceScene& scene, std::size_t i) {
  GaussianShape g;
  if (scene.shape_half) {
    const float4 p = __ldg(scene.position_dc_r + i);
    const uint4 h = __ldg(scene.shape_record + i);
    g = GaussianShape{{p.x, p.y, p.z}, high_half(h.w),
                      {low_half(h.x), high_half(h.x), low_half(h.y), high_half(h.y)},
                      {low_half(h.z), high_half(h.z), low_half(h.w)}, p.w};
  } else {
    const float4 po = __ldg(scene.position_opacity + i), q = __ldg(scene.rotation + i);
    const float4 sd = __ldg(scene.scale_dc_r + i);
    g = GaussianShape{{po.x, po.y, po.z}, po.w, {q.x, q.y, q.z, q.w}, {sd.x, sd.y, sd.z}, sd.w};
  }
  return g;
}

}  // namespace cuda
}  // namespace flashgs
