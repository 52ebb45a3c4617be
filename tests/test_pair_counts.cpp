// Gaussian-tile pair counts on the real scenes against the two published rules, each written
// here independently in double precision from its description (../shared/ANCHORS.md):
// - 3DGS: square box of radius ceil(3 sqrt(mid + sqrt(max(0.1, mid^2 - det)))), every tile of
//   the box;
// - FlashGS: extent 2 ln(256 o), tiles of its per-axis box that the ellipse meets (the
//   rectangle of a tile's pixel centres, not clipped to the image), Gaussians with
//   255 o < 1 culled.
// Our baseline must count what 3DGS counts (up to float rounding at box edges), and our
// flash path no more than FlashGS on the same input: the kv target of the CUDA issue, checked
// where the measured FlashGS figures cannot be (they came from another harness's inputs).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "flashgs/frame_params.h"
#include "flashgs/gaussian_math.h"
#include "test_support.h"

namespace flashgs {
namespace {

struct ViewGaussian {
  double mean_x, mean_y;
  double cov_xx, cov_xy, cov_yy;  // dilated 2D covariance
};

// 3DGS's projection in double: Jacobian at the direction clamped to 1.3 tan(fov / 2), 0.3
// dilation. False when culled by the near plane.
bool project_double(const Camera& cam, const Scene& scene, std::size_t i, ViewGaussian& out) {
  double d[3], t[3];
  for (int k = 0; k < 3; ++k) d[k] = double(scene.positions[i * 3 + k]) - cam.position[k];
  for (int r = 0; r < 3; ++r)
    t[r] = cam.rotation[r * 3] * d[0] + cam.rotation[r * 3 + 1] * d[1] + cam.rotation[r * 3 + 2] * d[2];
  if (!(t[2] > 0.2)) return false;
  const double lim_x = 1.3 * cam.width / (2.0 * cam.fx), lim_y = 1.3 * cam.height / (2.0 * cam.fy);
  const double tx = std::clamp(t[0] / t[2], -lim_x, lim_x), ty = std::clamp(t[1] / t[2], -lim_y, lim_y);
  const double jac[2][3] = {{cam.fx / t[2], 0, -cam.fx * tx / t[2]}, {0, cam.fy / t[2], -cam.fy * ty / t[2]}};
  const double w = scene.rotations[i * 4], x = scene.rotations[i * 4 + 1], y = scene.rotations[i * 4 + 2],
               z = scene.rotations[i * 4 + 3];
  const double rot[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                         2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                         2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
  double m[2][3] = {};
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) {
        double jw = 0;  // (J W)[r][k]
        for (int j = 0; j < 3; ++j) jw += jac[r][j] * cam.rotation[j * 3 + k];
        m[r][c] += jw * rot[k * 3 + c] * scene.scales[i * 3 + c];
      }
  out.cov_xx = m[0][0] * m[0][0] + m[0][1] * m[0][1] + m[0][2] * m[0][2] + 0.3;
  out.cov_xy = m[0][0] * m[1][0] + m[0][1] * m[1][1] + m[0][2] * m[1][2];
  out.cov_yy = m[1][0] * m[1][0] + m[1][1] * m[1][1] + m[1][2] * m[1][2] + 0.3;
  out.mean_x = cam.fx * t[0] / t[2] + cam.cx;
  out.mean_y = cam.fy * t[1] / t[2] + cam.cy;
  return true;
}

long long count_3dgs_rule(const Camera& cam, const Scene& scene) {
  const int grid_x = (cam.width + 15) / 16, grid_y = (cam.height + 15) / 16;
  long long pairs = 0;
  for (std::size_t i = 0; i < scene.size(); ++i) {
    ViewGaussian g;
    if (!project_double(cam, scene, i, g)) continue;
    const double det = g.cov_xx * g.cov_yy - g.cov_xy * g.cov_xy;
    if (det == 0) continue;
    const double mid = 0.5 * (g.cov_xx + g.cov_yy);
    const double radius = std::ceil(3.0 * std::sqrt(mid + std::sqrt(std::max(0.1, mid * mid - det))));
    auto tile = [](double v, int grid) { return std::min(grid, std::max(0, int(v / 16))); };
    const int x0 = tile(g.mean_x - radius, grid_x), x1 = tile(g.mean_x + radius + 15, grid_x);
    const int y0 = tile(g.mean_y - radius, grid_y), y1 = tile(g.mean_y + radius + 15, grid_y);
    pairs += (long long)(x1 - x0) * (y1 - y0);
  }
  return pairs;
}

// Smallest q = d^T C d over the rectangle [x0, x1] x [y0, y1] of offsets: zero when it holds
// the centre, else on one of its edges, each a parabola minimised in closed form.
double min_q_over_rect(double a, double b, double c, double x0, double x1, double y0, double y1) {
  if (x0 <= 0 && x1 >= 0 && y0 <= 0 && y1 >= 0) return 0;
  auto q = [&](double dx, double dy) { return a * dx * dx + 2 * b * dx * dy + c * dy * dy; };
  double best = INFINITY;
  for (double dx : {x0, x1}) best = std::min(best, q(dx, std::clamp(-b * dx / c, y0, y1)));
  for (double dy : {y0, y1}) best = std::min(best, q(std::clamp(-b * dy / a, x0, x1), dy));
  return best;
}

long long count_flashgs_rule(const Camera& cam, const Scene& scene) {
  const int grid_x = (cam.width + 15) / 16, grid_y = (cam.height + 15) / 16;
  long long pairs = 0;
  for (std::size_t i = 0; i < scene.size(); ++i) {
    const double opacity = scene.opacities[i];
    if (255.0 * opacity < 1.0) continue;
    ViewGaussian g;
    if (!project_double(cam, scene, i, g)) continue;
    const double det = g.cov_xx * g.cov_yy - g.cov_xy * g.cov_xy;
    const double a = g.cov_yy / det, b = -g.cov_xy / det, c = g.cov_xx / det;  // conic
    const double power = std::log(256.0 * opacity), threshold = 2.0 * power;
    const int half_w = int(std::sqrt(2.0 * g.cov_xx * power) + 1.0);
    const int half_h = int(std::sqrt(2.0 * g.cov_yy * power) + 1.0);
    auto first = [](double v, int grid) { return std::min(grid, std::max(0, int(v / 16))); };
    auto last = [](double v, int grid) { return std::min(grid, std::max(0, int(v / 16) + 1)); };
    const int x0 = first(g.mean_x - half_w, grid_x), x1 = last(g.mean_x + half_w, grid_x);
    const int y0 = first(g.mean_y - half_h, grid_y), y1 = last(g.mean_y + half_h, grid_y);
    for (int ty = y0; ty < y1; ++ty)
      for (int tx = x0; tx < x1; ++tx) {
        const double px = tx * 16.0 - g.mean_x, py = ty * 16.0 - g.mean_y;
        if (min_q_over_rect(a, b, c, px, px + 15, py, py + 15) <= threshold) ++pairs;
      }
  }
  return pairs;
}

// Our rule: gm::project and the exact tile test, as both backends run them (their pair
// counts are tested equal to each other in test_cpu_render / test_cuda_render).
// `flashgs_input`: leave out the Gaussians FlashGS culls (255 o < 1), for a count on the same
// input as its rule.
long long count_ours(const Camera& cam, const Scene& scene, const RenderOptions& options,
                     bool flashgs_input = false) {
  const gm::CameraParams params = make_camera_params(cam);
  const gm::GeometryParams geometry = make_geometry_params(options);
  long long pairs = 0;
  for (std::size_t i = 0; i < scene.size(); ++i) {
    if (flashgs_input && 255.0 * scene.opacities[i] < 1.0) continue;
    gm::Footprint f;
    if (gm::project(params, geometry, &scene.positions[i * 3], &scene.scales[i * 3], &scene.rotations[i * 4],
                    scene.opacities[i], f) != gm::kVisible)
      continue;
    if (!options.uses_exact_tile_test()) {
      pairs += (long long)(f.tile_x1 - f.tile_x0) * (f.tile_y1 - f.tile_y0);
      continue;
    }
    for (int ty = f.tile_y0; ty < f.tile_y1; ++ty)
      for (int tx = f.tile_x0; tx < f.tile_x1; ++tx)
        pairs += gm::footprint_touches_tile(f, tx, ty, cam.width, cam.height) ? 1 : 0;
  }
  return pairs;
}

class PairCounts : public ::testing::TestWithParam<const char*> {};

TEST_P(PairCounts, BaselineCountsWhat3dgsCountsAndFlashNoMoreThanFlashGs) {
  if (test::shared_scene_dir(GetParam()).empty()) GTEST_SKIP() << "../shared/scenes/" << GetParam() << " is absent";
  const auto scene = test::load_shared_scene(GetParam());
  const auto cameras = test::load_shared_cameras(GetParam());
  const RenderOptions flash;  // defaults: every optimisation on, tau = 1/255
  RenderOptions flash_same_tau;  // FlashGS's tau
  flash_same_tau.tau = 1.0f / 256.0f;
  const RenderOptions baseline = RenderOptions::baseline();
  long long ours_flash_total = 0, flashgs_total = 0;
  for (std::size_t k = 0; k < cameras.size() && k <= 34; k += 6) {
    for (const auto& size : {std::pair<int, int>{1920, 1080}, std::pair<int, int>{3840, 2160}}) {
      const Camera cam = cameras[k].resized(size.first, size.second);
      const long long ours_base = count_ours(cam, *scene, baseline);
      const long long ref_base = count_3dgs_rule(cam, *scene);
      // Float vs double rounding moves a box edge by a tile now and then (measured <= 5.1e-6;
      // without the 0.1 floor of 3DGS's eigenvalue 1.5e-4 on pc_playbot): 1e-5 allowed.
      EXPECT_NEAR(double(ours_base), double(ref_base), 1e-5 * double(ref_base))
          << GetParam() << " camera " << k << " " << size.first << "x" << size.second;
      const long long ours = count_ours(cam, *scene, flash);
      const long long ours_same_tau = count_ours(cam, *scene, flash_same_tau, true);
      const long long flashgs = count_flashgs_rule(cam, *scene);
      EXPECT_LE(ours, flashgs) << GetParam() << " camera " << k << " " << size.first << "x" << size.second;
      // At FlashGS's own tau and on its input (without 1/256 <= o < 1/255, which it culls)
      // both rules select the same tiles up to rounding: 0.005% allowed for that.
      EXPECT_LE(double(ours_same_tau), 1.00005 * double(flashgs))
          << GetParam() << " camera " << k << " " << size.first << "x" << size.second << " at tau 1/256";
      ours_flash_total += ours;
      flashgs_total += flashgs;
      std::printf("%s camera %zu %dx%d: baseline %lld (3DGS rule %lld), flash %lld, at tau 1/256 %lld "
                  "(FlashGS rule %lld)\n",
                  GetParam(), k, size.first, size.second, ours_base, ref_base, ours, ours_same_tau, flashgs);
    }
  }
  EXPECT_GT(flashgs_total, 0);
  EXPECT_LE(ours_flash_total, flashgs_total);
}

INSTANTIATE_TEST_SUITE_P(RealScenes, PairCounts,
                         ::testing::Values("pc_biker", "pc_playbot", "pc_guitar", "v3dg_donut", "kacytran_try"));

}  // namespace
}  // namespace flashgs
