// fp64 brute-force reference renderer (see reference_renderer.h).
#include "flashgs/reference_renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "flashgs/gaussian_math.h"
#include "parallel_errors.h"

namespace flashgs {
namespace {

// The rule's constants are the float values every backend compares against (0.2f, 0.3f,
// 0.99f, 1/255.f, 1e-4f), held exactly in double: the reference differs from a backend only
// in arithmetic, not in where a threshold sits. With decimal doubles instead, a Gaussian at
// z = 0.2f (= 0.2000000030) was culled by the backends and drawn by the reference, and two
// alpha = 0.99 layers ((1 - 0.99)^2 = 1e-4, the stop threshold) stopped on opposite sides.
constexpr double kNearZ = gm::kNearZ;
constexpr double kAlphaMax = gm::kAlphaMax;
constexpr double kAlphaMin = gm::kAlphaMin;
constexpr double kTransmittanceMin = gm::kTransmittanceMin;
constexpr double kFloatMax = 3.4028234663852886e38;

struct RefGaussian {
  double mean_x, mean_y, depth;
  float sort_depth;  // the backends' float view depth (their sort key)
  double a, b, c;  // conic
  double opacity;
  double rgb[3];
  std::size_t index;
  int px0, px1, py0, py1;  // the pixels it may reach: [px0, px1) x [py0, py1)
};

// 3DGS's pixel rectangle (getRect over its radius), in double: the pixels of tiles
// [trunc((m - r) / 16), trunc((m + r + 15) / 16)) clamped to the grid. a, c: the diagonal of
// the dilated covariance; det its determinant.
void box_3dgs(const Camera& camera, double mean_x, double mean_y, double a, double c, double det, RefGaussian& g) {
  const double mid = 0.5 * (a + c);
  const double lambda = mid + std::sqrt(std::max(double(gm::kBaselineSpreadFloor), mid * mid - det));
  const double radius = std::ceil(gm::kBaselineSigmas * std::sqrt(lambda));
  const double ts = gm::kTileSize;
  const double grid_x = (camera.width + gm::kTileSize - 1) / gm::kTileSize;
  const double grid_y = (camera.height + gm::kTileSize - 1) / gm::kTileSize;
  auto tile = [&](double v, double grid) { return static_cast<int>(std::clamp(std::trunc(v / ts), 0.0, grid)); };
  g.px0 = gm::kTileSize * tile(mean_x - radius, grid_x);
  g.px1 = gm::kTileSize * tile(mean_x + radius + ts - 1, grid_x);
  g.py0 = gm::kTileSize * tile(mean_y - radius, grid_y);
  g.py1 = gm::kTileSize * tile(mean_y + radius + ts - 1, grid_y);
}

// Real SH in double, same basis as gaussian_math.h.
void sh_rgb_double(const Scene& scene, std::size_t i, int degree, const double dir[3], double rgb[3]) {
  const double x = dir[0], y = dir[1], z = dir[2];
  double basis[16] = {model::kShC0};
  if (degree > 0) {
    basis[1] = -model::kShC1 * y;
    basis[2] = model::kShC1 * z;
    basis[3] = -model::kShC1 * x;
  }
  if (degree > 1) {
    const double xx = x * x, yy = y * y, zz = z * z;
    basis[4] = model::kShC2_0 * x * y;
    basis[5] = model::kShC2_1 * y * z;
    basis[6] = model::kShC2_2 * (2 * zz - xx - yy);
    basis[7] = model::kShC2_3 * x * z;
    basis[8] = model::kShC2_4 * (xx - yy);
    if (degree > 2) {
      basis[9] = model::kShC3_0 * y * (3 * xx - yy);
      basis[10] = model::kShC3_1 * x * y * z;
      basis[11] = model::kShC3_2 * y * (4 * zz - xx - yy);
      basis[12] = model::kShC3_3 * z * (2 * zz - 3 * xx - 3 * yy);
      basis[13] = model::kShC3_4 * x * (4 * zz - xx - yy);
      basis[14] = model::kShC3_5 * z * (xx - yy);
      basis[15] = model::kShC3_6 * x * (xx - 3 * yy);
    }
  }
  const int rest_n = scene.sh_rest_per_gaussian();
  for (int ch = 0; ch < 3; ++ch) {
    double sum = basis[0] * scene.sh_dc[i * 3 + ch];
    for (int k = 1; k < (degree + 1) * (degree + 1); ++k)
      sum += basis[k] * scene.sh_rest[i * rest_n + (k - 1) * 3 + ch];
    rgb[ch] = std::max(sum + 0.5, 0.0);
  }
}

// Minimum of q(d) = a dx^2 + 2 b dx dy + c dy^2 over a rectangle of offsets (0 if it holds
// the centre); see gm::whitened_ellipse_meets_rect.
double min_q_over_rect(const RefGaussian& g, double dx0, double dx1, double dy0, double dy1) {
  auto q = [&](double dx, double dy) { return g.a * dx * dx + 2 * g.b * dx * dy + g.c * dy * dy; };
  const bool inside_x = dx0 <= 0 && dx1 >= 0, inside_y = dy0 <= 0 && dy1 >= 0;
  if (inside_x && inside_y) return 0;
  double best = std::numeric_limits<double>::infinity();
  if (!inside_x) {
    const double dx = dx0 > 0 ? dx0 : dx1;
    best = std::min(best, q(dx, std::clamp(-g.b * dx / g.c, dy0, dy1)));
  }
  if (!inside_y) {
    const double dy = dy0 > 0 ? dy0 : dy1;
    best = std::min(best, q(std::clamp(-g.b * dy / g.a, dx0, dx1), dy));
  }
  return best;
}

}  // namespace

Image render_reference(const Scene& scene, const Camera& camera, const RenderOptions& options,
                       PixelWindow window, ReferenceFootprint footprint) {
  if (window.width < 0) window.width = camera.width;
  if (window.height < 0) window.height = camera.height;
  const int degree = std::max(0, std::min(scene.sh_degree, options.sh_degree_cap));
  // The kernel's dilation, the float value the backends add, held exactly.
  const double dilation = options.kernel.dilation();
  const bool compensate = options.kernel.compensates_opacity();
  double rot[9], centre[3];
  for (int k = 0; k < 9; ++k) rot[k] = camera.rotation[k];
  for (int k = 0; k < 3; ++k) centre[k] = camera.position[k];

  std::vector<RefGaussian> gaussians;
  for (std::size_t i = 0; i < scene.size(); ++i) {
    double d[3], v[3];
    for (int k = 0; k < 3; ++k) d[k] = static_cast<double>(scene.positions[i * 3 + k]) - centre[k];
    for (int r = 0; r < 3; ++r) v[r] = rot[r * 3] * d[0] + rot[r * 3 + 1] * d[1] + rot[r * 3 + 2] * d[2];
    if (!(v[2] > kNearZ)) continue;
    const double raw_opacity = scene.opacities[i];
    if (!(raw_opacity >= kAlphaMin)) continue;  // alpha <= opacity can never reach 1/255
    // Sigma_2D = M M^T, M = J W R S (double precision throughout).
    const double qw = scene.rotations[i * 4], qx = scene.rotations[i * 4 + 1],
                 qy = scene.rotations[i * 4 + 2], qz = scene.rotations[i * 4 + 3];
    const double r[9] = {1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz),     2 * (qx * qz + qw * qy),
                         2 * (qx * qy + qw * qz),     1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx),
                         2 * (qx * qz - qw * qy),     2 * (qy * qz + qw * qx),     1 - 2 * (qx * qx + qy * qy)};
    const double fx = camera.fx, fy = camera.fy, z = v[2];
    // The Jacobian at the direction clamped to the widened frustum (gm::frustum_clamped_direction).
    const double width = camera.width, height = camera.height;
    const double tx = std::clamp(v[0] / z, -(camera.cx + 0.5 + model::kFrustumMargin * width) / fx,
                                 (width - 0.5 - camera.cx + model::kFrustumMargin * width) / fx);
    const double ty = std::clamp(v[1] / z, -(camera.cy + 0.5 + model::kFrustumMargin * height) / fy,
                                 (height - 0.5 - camera.cy + model::kFrustumMargin * height) / fy);
    const double j00 = fx / z, j02 = -fx * tx / z, j11 = fy / z, j12 = -fy * ty / z;
    double t0[3], t1[3];
    for (int k = 0; k < 3; ++k) {
      t0[k] = j00 * rot[k] + j02 * rot[6 + k];
      t1[k] = j11 * rot[3 + k] + j12 * rot[6 + k];
    }
    double m0[3], m1[3];
    for (int k = 0; k < 3; ++k) {
      const double s = scene.scales[i * 3 + k];
      const double ax = r[k] * s, ay = r[3 + k] * s, az = r[6 + k] * s;
      m0[k] = t0[0] * ax + t0[1] * ay + t0[2] * az;
      m1[k] = t1[0] * ax + t1[1] * ay + t1[2] * az;
    }
    const double a = m0[0] * m0[0] + m0[1] * m0[1] + m0[2] * m0[2] + dilation;
    const double b = m0[0] * m1[0] + m0[1] * m1[1] + m0[2] * m1[2];
    const double c = m1[0] * m1[0] + m1[1] * m1[1] + m1[2] * m1[2] + dilation;
    const double n01 = m0[0] * m1[1] - m0[1] * m1[0], n02 = m0[0] * m1[2] - m0[2] * m1[0],
                 n12 = m0[1] * m1[2] - m0[2] * m1[1];
    const double det_undilated = n01 * n01 + n02 * n02 + n12 * n12;
    const double det = det_undilated + dilation * (a + c - 2 * dilation) + dilation * dilation;
    if (!std::isfinite(det) || !(det > 0) || !std::isfinite(a) || !std::isfinite(c)) continue;
    // The anti-aliased kernel's opacity (gm::project): the integral of the undilated Gaussian kept.
    const double opacity = compensate ? raw_opacity * std::sqrt(det_undilated / det) : raw_opacity;
    // The backends cull (FrameStats::culled_degenerate) a footprint whose covariance squared
    // leaves float range (screen sigma above ~4e9 px, e.g. a log-scale of 50 in a file): it
    // is not representable there. The reference applies the same documented rule, so that it
    // judges what the backends draw; `flashgs check` reports how many were culled.
    if (det > kFloatMax || (a + c) * (a + c) > kFloatMax) continue;
    RefGaussian g;
    g.mean_x = fx * v[0] / z + camera.cx;
    g.mean_y = fy * v[1] / z + camera.cy;
    g.depth = z;
    {
      // The order is part of the rule: the backends sort by the view depth they compute in
      // float (gm::to_view). The double depth rounded to float can differ from it by an ulp,
      // which swaps two nearly coincident layers (measured: 0.021 on a pc_playbot pixel).
      gm::CameraParams cam_f{};
      for (int k = 0; k < 9; ++k) cam_f.rotation[k] = camera.rotation[k];
      for (int k = 0; k < 3; ++k) cam_f.position[k] = camera.position[k];
      float v_f[3];
      gm::to_view(cam_f, &scene.positions[i * 3], v_f);
      g.sort_depth = v_f[2];
    }
    g.a = c / det;
    g.b = -b / det;
    g.c = a / det;
    g.opacity = opacity;
    g.index = i;
    if (!std::isfinite(g.mean_x) || !std::isfinite(g.mean_y)) continue;
    g.px0 = g.py0 = std::numeric_limits<int>::min();
    g.px1 = g.py1 = std::numeric_limits<int>::max();
    if (footprint == ReferenceFootprint::box_3dgs) {
      box_3dgs(camera, g.mean_x, g.mean_y, a, c, det, g);
      if (g.px1 <= window.x0 || g.px0 >= window.x0 + window.width || g.py1 <= window.y0 ||
          g.py0 >= window.y0 + window.height)
        continue;
    }
    // Skip exactly the Gaussians whose alpha stays below 1/255 over the whole window.
    const double q_min = min_q_over_rect(g, window.x0 - g.mean_x, window.x0 + window.width - 1 - g.mean_x,
                                         window.y0 - g.mean_y, window.y0 + window.height - 1 - g.mean_y);
    if (std::min(kAlphaMax, opacity * std::exp(-0.5 * q_min)) < kAlphaMin) continue;
    double dir[3];
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int k = 0; k < 3; ++k) dir[k] = len > 0 ? d[k] / len : 0.0;
    sh_rgb_double(scene, i, degree, dir, g.rgb);
    gaussians.push_back(g);
  }
  std::sort(gaussians.begin(), gaussians.end(), [](const RefGaussian& l, const RefGaussian& r) {
    // The float depths the backends sort by, then the index: the same order.
    const float lf = l.sort_depth, rf = r.sort_depth;
    return lf != rf ? lf < rf : l.index < r.index;
  });

  Image image;
  image.resize(window.width, window.height);
  ParallelErrors errors;
#pragma omp parallel for schedule(dynamic, 1)
  for (int y = 0; y < window.height; ++y)
    errors.capture([&] {
      for (int x = 0; x < window.width; ++x) {
        const double px = window.x0 + x, py = window.y0 + y;
        double t = 1.0, rgb[3] = {0, 0, 0};
        for (const RefGaussian& g : gaussians) {
          if (px < g.px0 || px >= g.px1 || py < g.py0 || py >= g.py1) continue;
          const double dx = px - g.mean_x, dy = py - g.mean_y;
          const double power = -0.5 * (g.a * dx * dx + g.c * dy * dy) - g.b * dx * dy;
          if (power > 0) continue;
          const double alpha = std::min(kAlphaMax, g.opacity * std::exp(power));
          if (alpha < kAlphaMin) continue;
          const double next_t = t * (1 - alpha);
          if (next_t < kTransmittanceMin) break;
          for (int ch = 0; ch < 3; ++ch) rgb[ch] += g.rgb[ch] * alpha * t;
          t = next_t;
        }
        float* out = image.pixel(x, y);
        for (int ch = 0; ch < 3; ++ch) out[ch] = static_cast<float>(rgb[ch] + t * options.background[ch]);
      }
    });
  errors.rethrow();
  return image;
}

Image crop_image(const Image& image, const PixelWindow& window) {
  Image out;
  out.resize(window.width, window.height);
  for (int y = 0; y < window.height; ++y)
    for (int x = 0; x < window.width; ++x) {
      const float* in = image.pixel(window.x0 + x, window.y0 + y);
      float* o = out.pixel(x, y);
      o[0] = in[0];
      o[1] = in[1];
      o[2] = in[2];
    }
  return out;
}

}  // namespace flashgs
