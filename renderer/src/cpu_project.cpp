// CPU project stage: cull, screen-space footprint and SH colour for every Gaussian.
#include <cmath>

#include "cpu_frame.h"
#include "parallel_errors.h"

namespace flashgs {
namespace cpu {
namespace {

// `dc` and `rest`: the scene's SH coefficients, or their half values (RenderOptions::fp16_sh).
template <int DEGREE>
void project_all(const Scene& scene, const float* dc, const float* rest, Frame& frame) {
  const std::int64_t n = static_cast<std::int64_t>(scene.size());
  const int rest_n = scene.sh_rest_per_gaussian();
  ParallelErrors errors;
#pragma omp parallel for schedule(static) num_threads(frame.threads)
  for (std::int64_t i = 0; i < n; ++i)
    errors.capture([&] {
      gm::Footprint& f = frame.footprints[i];
      const float opacity = scene.opacities[i];
      const gm::CullReason reason =
          gm::project(frame.camera, frame.geometry, &scene.positions[i * 3], &scene.scales[i * 3],
                      &scene.rotations[i * 4], opacity, f);
      frame.cull[i] = reason;
      if (reason != gm::kVisible) return;
      BlendGaussian& g = frame.blend_data[i];
      g.mean_x = f.mean_x;
      g.mean_y = f.mean_y;
      for (int k = 0; k < 4; ++k) g.whiten[k] = f.whiten[k];
      g.opacity = opacity;
      const float power_cut = opacity > 0 ? std::log(gm::kAlphaMin / opacity) - 1e-3f : 0.0f;
      g.log2_opacity = std::log2(opacity);
      // (a c - b^2) / a = det(W)^2 / a (Lagrange's identity); det(W) = w0 w3 - w1 w2 adds two
      // non-negative terms, so a needle (a nearly singular conic) keeps an accurate row minimum.
      const double w0 = f.whiten[0], w1 = f.whiten[1], w2 = f.whiten[2], w3 = f.whiten[3];
      const double conic_a = w0 * w0 + w2 * w2, det_w = w0 * w3 - w1 * w2;
      g.row_q_coeff = static_cast<float>(det_w * det_w / conic_a);
      g.row_slope = static_cast<float>(-(w0 * w1 + w2 * w3) / conic_a);
      g.inv_conic_a = static_cast<float>(1.0 / conic_a);
      g.q_cut = -2.0f * power_cut;  // exact: power_cut = -0.5 q_cut
      gm::sh_to_rgb<DEGREE>(frame.camera.position, &scene.positions[i * 3], dc + i * 3,
                            DEGREE > 0 ? rest + i * rest_n : nullptr, g.rgb);
    });
  errors.rethrow();
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

void project(const Scene& scene, const RenderOptions& options, Frame& frame, FrameStats& stats) {
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
  switch (degree) {
    case 0: project_all<0>(scene, dc, rest, frame); break;
    case 1: project_all<1>(scene, dc, rest, frame); break;
    case 2: project_all<2>(scene, dc, rest, frame); break;
    default: project_all<3>(scene, dc, rest, frame); break;
  }
  std::uint64_t near = 0, offscreen = 0, low_opacity = 0, degenerate = 0;
  const std::int64_t count = static_cast<std::int64_t>(n);
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
