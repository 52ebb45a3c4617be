// CPU project stage: cull, screen-space footprint and SH colour for every Gaussian.
#include <algorithm>
#include <cmath>

#include "cpu_frame.h"
#include "parallel_errors.h"

namespace flashgs {
namespace cpu {
namespace {

// The scalar reference for one Gaussian.
template <int DEGREE>
void project_range(const SceneArrays& scene, Frame& frame, std::int64_t begin, std::int64_t end) {
  for (std::int64_t i = begin; i < end; ++i) {
    gm::Footprint& f = frame.footprints[i];
    const float opacity = scene.opacities[i];
    const gm::CullReason reason = gm::project(frame.camera, frame.geometry, &scene.positions[i * 3],
                                              &scene.scales[i * 3], &scene.rotations[i * 4], opacity, f);
    frame.cull[i] = reason;
    if (reason != gm::kVisible) continue;
    frame.depth_bits[i] = gm::depth_bits(f.depth);
    BlendGaussian& g = frame.blend_data[i];
    g.mean_x = f.mean_x;
    g.mean_y = f.mean_y;
    for (int k = 0; k < 4; ++k) g.whiten[k] = f.whiten[k];
    set_opacity_terms(frame, i, f.opacity, g);
    set_row_pruning(g);
    gm::sh_to_rgb<DEGREE>(frame.camera.position, &scene.positions[i * 3], scene.dc + i * 3,
                          DEGREE > 0 ? scene.rest + i * scene.rest_n : nullptr, g.rgb);
  }
}

// log2_opacity and q_cut depend on the opacity alone: under the classic kernel computed once
// per scene (and precision), not per frame.
void cache_opacity_terms(const SceneArrays& scene, Frame& frame) {
  const std::size_t n = static_cast<std::size_t>(scene.count);
  if (frame.opacity_terms_of == scene.opacities && frame.opacity_terms_size == n) return;
  frame.log2_opacity.resize(n);
  frame.q_cut.resize(n);
#pragma omp parallel for schedule(static) num_threads(frame.threads)
  for (std::int64_t i = 0; i < scene.count; ++i) {
    opacity_terms(scene.opacities[i], frame.log2_opacity[i], frame.q_cut[i]);
  }
  frame.opacity_terms_of = scene.opacities;
  frame.opacity_terms_size = n;
}

// `in` rounded to half values into `out` (the CUDA backend stores the halves instead).
void round_to_halves(const std::vector<float>& in, std::vector<float>& out, int threads) {
  out.resize(in.size());
  const std::int64_t n = static_cast<std::int64_t>(in.size());
#pragma omp parallel for schedule(static) num_threads(threads)
  for (std::int64_t k = 0; k < n; ++k) out[k] = gm::round_to_half(in[k]);
}

// The scene's SH coefficients as half values, rounded once per scene: a frame then costs what
// an exact one does.
void round_sh_to_halves(const Scene& scene, Frame& frame) {
  if (frame.half_sh_of == &scene) return;
  round_to_halves(scene.sh_dc, frame.half_sh_dc, frame.threads);
  round_to_halves(scene.sh_rest, frame.half_sh_rest, frame.threads);
  frame.half_sh_of = &scene;
}

// The same for the rotations, scales and opacities.
void round_shape_to_halves(const Scene& scene, Frame& frame) {
  if (frame.half_shape_of == &scene) return;
  round_to_halves(scene.rotations, frame.half_rotations, frame.threads);
  round_to_halves(scene.scales, frame.half_scales, frame.threads);
  round_to_halves(scene.opacities, frame.half_opacities, frame.threads);
  frame.half_shape_of = &scene;
}

// What the frame reads of the scene under `options`' precision.
SceneArrays scene_arrays(const Scene& scene, const RenderOptions& options, Frame& frame) {
  SceneArrays a{static_cast<std::int64_t>(scene.size()),
                scene.positions.data(),
                scene.scales.data(),
                scene.rotations.data(),
                scene.opacities.data(),
                scene.sh_dc.data(),
                scene.sh_rest.data(),
                scene.sh_rest_per_gaussian()};
  if (options.fp16_sh) {
    round_sh_to_halves(scene, frame);
    a.dc = frame.half_sh_dc.data();
    a.rest = frame.half_sh_rest.data();
  }
  if (options.fp16_shape) {
    round_shape_to_halves(scene, frame);
    a.scales = frame.half_scales.data();
    a.rotations = frame.half_rotations.data();
    a.opacities = frame.half_opacities.data();
  }
  return a;
}

}  // namespace

void project_block_scalar(const SceneArrays& scene, int degree, Frame& frame, std::int64_t begin, std::int64_t end) {
  switch (degree) {
    case 0: project_range<0>(scene, frame, begin, end); break;
    case 1: project_range<1>(scene, frame, begin, end); break;
    case 2: project_range<2>(scene, frame, begin, end); break;
    default: project_range<3>(scene, frame, begin, end); break;
  }
}

void project(const Scene& scene, const RenderOptions& options, Frame& frame, FrameStats& stats,
             ProjectKernel kernel) {
  const std::size_t n = scene.size();
  if (frame.footprints.size() < n) {
    frame.footprints.resize(n);
    frame.cull.resize(n);
    frame.blend_data.resize(n);
    frame.depth_bits.resize(n);
  }
  // A scene pays only for the SH bands it has (and the viewer's cap).
  const int degree = std::max(0, std::min(scene.sh_degree, options.sh_degree_cap));
  const SceneArrays arrays = scene_arrays(scene, options, frame);
  cache_opacity_terms(arrays, frame);
  // Blocks of Gaussians (a multiple of every SIMD width), so that only the last one has a tail
  // for the SIMD kernel's scalar code.
  constexpr std::int64_t kBlock = 1024;
  const std::int64_t count = static_cast<std::int64_t>(n), blocks = (count + kBlock - 1) / kBlock;
  const auto project_block = kernel == ProjectKernel::simd ? project_block_simd : project_block_scalar;
  ParallelErrors errors;
  // Taken dynamically: the visible Gaussians, which cost the most, are uneven along the scene's
  // order (pc_playbot camera 0 at 1080p: 63% of them in the first half).
#pragma omp parallel for schedule(dynamic, 1) num_threads(frame.threads)
  for (std::int64_t b = 0; b < blocks; ++b)
    errors.capture([&] {
      project_block(arrays, degree, frame, b * kBlock, std::min(count, (b + 1) * kBlock));
    });
  errors.rethrow();
  std::uint64_t visible = 0, near = 0, offscreen = 0, low_opacity = 0, degenerate = 0;
#pragma omp parallel for schedule(static) num_threads(frame.threads) \
    reduction(+ : visible, near, offscreen, low_opacity, degenerate)
  for (std::int64_t i = 0; i < count; ++i) {
    const std::uint8_t reason = frame.cull[i];
    visible += reason == gm::kVisible;
    near += reason == gm::kCulledNear;
    offscreen += reason == gm::kCulledOffscreen;
    low_opacity += reason == gm::kCulledLowOpacity;
    degenerate += reason == gm::kCulledDegenerate;
  }
  stats.culled_near += near;
  stats.culled_offscreen += offscreen;
  stats.culled_low_opacity += low_opacity;
  stats.culled_degenerate += degenerate;
  frame.visible_count = static_cast<std::size_t>(visible);
}

}  // namespace cpu
}  // namespace flashgs
