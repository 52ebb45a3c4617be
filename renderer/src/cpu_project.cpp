// CPU project stage: cull, screen-space footprint and SH colour for every Gaussian.
#include <algorithm>
#include <cmath>

#include "cpu_frame.h"
#include "parallel_errors.h"

namespace flashgs {
namespace cpu {
namespace {

// The scalar reference for one Gaussian. `dc` and `rest`: the scene's SH coefficients, or
// their half values (RenderOptions::fp16_sh).
template <int DEGREE>
void project_range(const Scene& scene, const float* dc, const float* rest, Frame& frame, std::int64_t begin,
                   std::int64_t end) {
  const int rest_n = scene.sh_rest_per_gaussian();
  for (std::int64_t i = begin; i < end; ++i) {
    gm::Footprint& f = frame.footprints[i];
    const float opacity = scene.opacities[i];
    const gm::CullReason reason = gm::project(frame.camera, frame.geometry, &scene.positions[i * 3],
                                              &scene.scales[i * 3], &scene.rotations[i * 4], opacity, f);
    frame.cull[i] = reason;
    if (reason != gm::kVisible) continue;
    BlendGaussian& g = frame.blend_data[i];
    g.mean_x = f.mean_x;
    g.mean_y = f.mean_y;
    for (int k = 0; k < 4; ++k) g.whiten[k] = f.whiten[k];
    g.opacity = opacity;
    g.log2_opacity = frame.log2_opacity[i];
    g.q_cut = frame.q_cut[i];
    set_row_pruning(g);
    gm::sh_to_rgb<DEGREE>(frame.camera.position, &scene.positions[i * 3], dc + i * 3,
                          DEGREE > 0 ? rest + i * rest_n : nullptr, g.rgb);
  }
}

// log2_opacity and q_cut depend on the opacity alone: computed once per scene, not per frame.
void cache_opacity_terms(const Scene& scene, Frame& frame) {
  if (frame.opacity_terms_of == &scene && frame.opacity_terms_size == scene.size()) return;
  const std::int64_t n = static_cast<std::int64_t>(scene.size());
  frame.log2_opacity.resize(scene.size());
  frame.q_cut.resize(scene.size());
#pragma omp parallel for schedule(static) num_threads(frame.threads)
  for (std::int64_t i = 0; i < n; ++i) {
    const float opacity = scene.opacities[i];
    const float power_cut = opacity > 0 ? std::log(gm::kAlphaMin / opacity) - 1e-3f : 0.0f;
    frame.log2_opacity[i] = std::log2(opacity);
    frame.q_cut[i] = -2.0f * power_cut;  // exact: power_cut = -0.5 q_cut
  }
  frame.opacity_terms_of = &scene;
  frame.opacity_terms_size = scene.size();
}

// The scene's SH coefficients as half values, rounded once per scene: a frame then costs what
// an exact one does (the CUDA backend stores them as halves instead).
void round_sh_to_halves(const Scene& scene, Frame& frame) {
  if (frame.half_sh_of == &scene) return;
  frame.half_sh_dc.resize(scene.sh_dc.size());
  frame.half_sh_rest.resize(scene.sh_rest.size());
  auto round_all = [&frame](const std::vector<float>& in, std::vector<float>& out) {
    const std::int64_t n = static_cast<std::int64_t>(in.size());
#pragma omp parallel for schedule(static) num_threads(frame.threads)
    for (std::int64_t k = 0; k < n; ++k) out[k] = gm::round_to_half(in[k]);
  };
  round_all(scene.sh_dc, frame.half_sh_dc);
  round_all(scene.sh_rest, frame.half_sh_rest);
  frame.half_sh_of = &scene;
}

}  // namespace

void project_block_scalar(const Scene& scene, const float* dc, const float* rest, int degree, Frame& frame,
                          std::int64_t begin, std::int64_t end) {
  switch (degree) {
    case 0: project_range<0>(scene, dc, rest, frame, begin, end); break;
    case 1: project_range<1>(scene, dc, rest, frame, begin, end); break;
    case 2: project_range<2>(scene, dc, rest, frame, begin, end); break;
    default: project_range<3>(scene, dc, rest, frame, begin, end); break;
  }
}

void project(const Scene& scene, const RenderOptions& options, Frame& frame, FrameStats& stats,
             ProjectKernel kernel) {
  const std::size_t n = scene.size();
  if (frame.footprints.size() < n) {
    frame.footprints.resize(n);
    frame.cull.resize(n);
    frame.blend_data.resize(n);
  }
  // A scene pays only for the SH bands it has (and the viewer's cap).
  const int degree = std::max(0, std::min(scene.sh_degree, options.sh_degree_cap));
  const float* dc = scene.sh_dc.data();
  const float* rest = scene.sh_rest.data();
  if (options.fp16_sh) {
    round_sh_to_halves(scene, frame);
    dc = frame.half_sh_dc.data();
    rest = frame.half_sh_rest.data();
  }
  cache_opacity_terms(scene, frame);
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
      project_block(scene, dc, rest, degree, frame, b * kBlock, std::min(count, (b + 1) * kBlock));
    });
  errors.rethrow();
  std::uint64_t near = 0, offscreen = 0, low_opacity = 0, degenerate = 0;
#pragma omp parallel for schedule(static) num_threads(frame.threads) \
    reduction(+ : near, offscreen, low_opacity, degenerate)
  for (std::int64_t i = 0; i < count; ++i) {
    const std::uint8_t reason = frame.cull[i];
    near += reason == gm::kCulledNear;
    offscreen += reason == gm::kCulledOffscreen;
    low_opacity += reason == gm::kCulledLowOpacity;
    degenerate += reason == gm::kCulledDegenerate;
  }
  stats.culled_near += near;
  stats.culled_offscreen += offscreen;
  stats.culled_low_opacity += low_opacity;
  stats.culled_degenerate += degenerate;
}

}  // namespace cpu
}  // namespace flashgs
