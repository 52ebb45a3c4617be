// CPU project stage: cull, screen-space footprint and SH colour for every Gaussian.
#include <cmath>

#include "cpu_frame.h"

namespace flashgs {
namespace cpu {
namespace {

template <int DEGREE>
void project_all(const Scene& scene, Frame& frame) {
  const std::int64_t n = static_cast<std::int64_t>(scene.size());
  const int rest_n = scene.sh_rest_per_gaussian();
  const float* rest = scene.sh_rest.data();
#pragma omp parallel for schedule(static) num_threads(frame.threads)
  for (std::int64_t i = 0; i < n; ++i) {
    gm::Footprint& f = frame.footprints[i];
    const float opacity = scene.opacities[i];
    const gm::CullReason reason =
        gm::project(frame.camera, frame.geometry, &scene.positions[i * 3], &scene.scales[i * 3],
                    &scene.rotations[i * 4], opacity, f);
    frame.cull[i] = reason;
    if (reason != gm::kVisible) continue;
    BlendGaussian& g = frame.blend_data[i];
    g.mean_x = f.mean_x;
    g.mean_y = f.mean_y;
    g.conic_a = f.conic_a;
    g.conic_b = f.conic_b;
    g.conic_c = f.conic_c;
    g.opacity = opacity;
    g.power_cut = opacity > 0 ? std::log(gm::kAlphaMin / opacity) - 1e-3f : 0.0f;
    // (a c - b^2) / a in double: the float products are exact there, so a nearly singular
    // conic (a needle on screen) keeps an accurate row minimum.
    const double a = f.conic_a, b = f.conic_b, c = f.conic_c;
    g.row_q_coeff = static_cast<float>(std::max(0.0, (a * c - b * b) / a));
    g.q_cut = -2.0f * g.power_cut;
    gm::sh_to_rgb<DEGREE>(frame.camera.position, &scene.positions[i * 3], &scene.sh_dc[i * 3],
                          DEGREE > 0 ? rest + i * rest_n : nullptr, g.rgb);
  }
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
  switch (degree) {
    case 0: project_all<0>(scene, frame); break;
    case 1: project_all<1>(scene, frame); break;
    case 2: project_all<2>(scene, frame); break;
    default: project_all<3>(scene, frame); break;
  }
  for (std::size_t i = 0; i < n; ++i) {
    switch (frame.cull[i]) {
      case gm::kCulledNear: stats.culled_near++; break;
      case gm::kCulledOffscreen: stats.culled_offscreen++; break;
      case gm::kCulledLowOpacity: stats.culled_low_opacity++; break;
      case gm::kCulledDegenerate: stats.culled_degenerate++; break;
      default: break;
    }
  }
}

}  // namespace cpu
}  // namespace flashgs
