// Per-Gaussian math shared bit for bit by the CPU backend and the CUDA kernels.
//
// Only +, -, *, /, sqrt, floor and ceil appear on the path that decides which tiles a
// Gaussian touches, so that the CPU and the GPU emit exactly the same Gaussian-tile pairs:
// those operations are correctly rounded on both. The CUDA files that include this header
// are compiled with -fmad=false and the host with -ffp-contract=off so that neither side
// fuses a multiply and an add the other does not. ln() is therefore our own (portable_log).
#pragma once

#include <math.h>

#include <cstdint>
#include <cstring>

#include "flashgs/model_constants.h"

#if defined(__CUDACC__)
#define FLASHGS_HD __host__ __device__ __forceinline__
#else
#define FLASHGS_HD inline
#endif

namespace flashgs {
namespace gm {

constexpr int kTileSize = 16;
constexpr float kNearZ = 0.2f;           // 3DGS culls at view-space z <= 0.2
constexpr float kAlphaMax = 0.99f;       // alpha clamp (3DGS)
constexpr float kAlphaMin = 1.0f / 255.0f;    // blend skips alpha below this
constexpr float kTransmittanceMin = 1e-4f;    // stop once T would fall below this
constexpr float kBaselineSigmas = 3.0f;
constexpr float kBaselineSpreadFloor = 0.1f;  // 3DGS: lambda = mid + sqrt(max(0.1, mid^2 - det))

// Camera in the form the kernels need (plain data, copied to the GPU by value).
struct CameraParams {
  float rotation[9];  // world-to-camera, row-major
  float position[3];  // camera centre
  float fx, fy, cx, cy;
  int width, height;
  int tiles_x, tiles_y;
  float frustum[4];   // frustum_limits(): per camera, not per Gaussian (four divisions)
};

// Which geometry a frame uses; derived from RenderOptions.
struct GeometryParams {
  bool baseline;             // original 3DGS box and tile rule
  bool opacity_radius;       // extent sqrt(2 ln(o / tau)) instead of 3 sigma
  bool tight_bbox;           // per-axis half widths instead of a square
  float tau;
  float dilation;            // px^2 added to the 2D covariance diagonal (SplatKernel::epsilon)
  bool compensate_opacity;   // the anti-aliased kernel: opacity * sqrt(det S / det(S + dilation I))
};

enum CullReason : std::uint8_t {
  kVisible = 0,
  kCulledNear = 1,
  kCulledOffscreen = 2,
  kCulledLowOpacity = 3,
  kCulledDegenerate = 4,
};
constexpr int kCullReasonCount = 5;  // the values above, 0 .. 4: counters are indexed by them

// The screen-space footprint of one Gaussian.
struct Footprint {
  float mean_x, mean_y;            // pixel-index coordinates (pixel centres are integers)
  float depth;                     // view-space z, > kNearZ
  float opacity;                   // what the blend multiplies: the anti-aliased kernel's compensated one
  float conic_a, conic_b, conic_c; // inverse 2D covariance: q = a dx^2 + 2 b dx dy + c dy^2
  float threshold;                 // the ellipse is q <= threshold
  int tile_x0, tile_y0;            // first tile of the box
  int tile_x1, tile_y1;            // one past the last tile of the box
  // The same q in whitened form, q = (w0 dx + w1 dy)^2 + (w2 dx + w3 dy)^2: rows are the
  // principal axes divided by their standard deviations. Evaluate q with this, not the
  // conic: for a needle (scale ratio >= 1e4 seen side-on) the conic is so ill-conditioned
  // (a c - b^2 ~ 1e-9 a c) that its float rounding alone puts q off by ~1e-7 a d^2, i.e. by
  // whole units 1000 px from the centre, and a dx^2 + 2 b dx dy + c dy^2 cancels there too.
  // The whitened form has no cancellation beyond the perpendicular distance itself, and
  // q >= 0 by construction (the conic form goes slightly negative on a needle's axis, where
  // 3DGS's "skip power > 0" then drops the Gaussian at its most opaque pixels).
  float whiten[4];
  // Where q is smallest along a vertical edge at offset dx: dy = edge_slope_x * dx
  // (= -conic_b / conic_c); along a horizontal edge: dx = edge_slope_y * dy. Divided once here,
  // not in each tile test.
  float edge_slope_x, edge_slope_y;
};

FLASHGS_HD float clampf(float v, float lo, float hi) { return v < lo ? lo : (v > hi ? hi : v); }
FLASHGS_HD float minf(float a, float b) { return a < b ? a : b; }
FLASHGS_HD float maxf(float a, float b) { return a > b ? a : b; }

FLASHGS_HD bool is_finite(float v) {
  // v - v is NaN for NaN and Inf; written without std::isfinite so that it behaves the same
  // under every compiler flag (fast-math would fold isfinite away).
  std::uint32_t bits;
  std::memcpy(&bits, &v, 4);
  return (bits & 0x7f800000u) != 0x7f800000u;
}

// Natural log from + - * / and the float's exponent field: the same result on CPU and GPU
// (library logf differs between them by an ulp, which would flip tile decisions).
// Accurate to a few ulp for normal positive x; returns -inf for x <= 0.
FLASHGS_HD float portable_log(float x) {
  if (!(x > 0.0f)) return -INFINITY;
  std::uint32_t bits;
  std::memcpy(&bits, &x, 4);
  int exponent = static_cast<int>((bits >> 23) & 0xffu) - 127;
  if (exponent == -127) {  // subnormal: scale into the normal range first
    float scaled = x * 8388608.0f;  // 2^23
    std::memcpy(&bits, &scaled, 4);
    exponent = static_cast<int>((bits >> 23) & 0xffu) - 127 - 23;
  }
  std::uint32_t mantissa_bits = (bits & 0x007fffffu) | 0x3f800000u;  // m in [1, 2)
  float m;
  std::memcpy(&m, &mantissa_bits, 4);
  if (m > 1.41421356f) {  // keep m in [sqrt(1/2), sqrt(2)) so the series converges fast
    m = m * 0.5f;
    exponent += 1;
  }
  // ln m = 2 atanh(s), s = (m - 1) / (m + 1), |s| < 0.172
  const float s = (m - 1.0f) / (m + 1.0f);
  const float s2 = s * s;
  const float series =
      s * (2.0f + s2 * (0.666666667f + s2 * (0.4f + s2 * (0.285714286f + s2 * 0.222222222f))));
  return static_cast<float>(exponent) * 0.693147181f + series;
}

// Normalised quaternion (w, x, y, z) to a rotation matrix, row-major.
FLASHGS_HD void quaternion_to_matrix(const float q[4], float m[9]) {
  const float w = q[0], x = q[1], y = q[2], z = q[3];
  m[0] = 1.0f - 2.0f * (y * y + z * z);
  m[1] = 2.0f * (x * y - w * z);
  m[2] = 2.0f * (x * z + w * y);
  m[3] = 2.0f * (x * y + w * z);
  m[4] = 1.0f - 2.0f * (x * x + z * z);
  m[5] = 2.0f * (y * z - w * x);
  m[6] = 2.0f * (x * z - w * y);
  m[7] = 2.0f * (y * z + w * x);
  m[8] = 1.0f - 2.0f * (x * x + y * y);
}

// View-space position: R (p - c). Subtracting first is exact when p and c are close
// (Sterbenz), so a scene at 1e7 seen from nearby keeps its relative precision.
FLASHGS_HD void to_view(const CameraParams& cam, const float p[3], float v[3]) {
  const float d0 = p[0] - cam.position[0], d1 = p[1] - cam.position[1],
              d2 = p[2] - cam.position[2];
  v[0] = cam.rotation[0] * d0 + cam.rotation[1] * d1 + cam.rotation[2] * d2;
  v[1] = cam.rotation[3] * d0 + cam.rotation[4] * d1 + cam.rotation[5] * d2;
  v[2] = cam.rotation[6] * d0 + cam.rotation[7] * d1 + cam.rotation[8] * d2;
}

// x/z and y/z clamped to the view frustum widened by 30% of its half-size on each side:
// 3DGS's limit 1.3 tan(fov / 2), written for any principal point (identical to it when the
// principal point is the image centre; the image spans pixel edges -0.5 .. width - 0.5).
// The limits as {x_lo, x_hi, y_lo, y_hi}: per camera (CameraParams::frustum).
FLASHGS_HD void frustum_limits(const CameraParams& cam, float limits[4]) {
  const float margin_x = static_cast<float>(model::kFrustumMargin) * static_cast<float>(cam.width);
  const float margin_y = static_cast<float>(model::kFrustumMargin) * static_cast<float>(cam.height);
  limits[0] = -(cam.cx + 0.5f + margin_x) / cam.fx;
  limits[1] = (static_cast<float>(cam.width) - 0.5f - cam.cx + margin_x) / cam.fx;
  limits[2] = -(cam.cy + 0.5f + margin_y) / cam.fy;
  limits[3] = (static_cast<float>(cam.height) - 0.5f - cam.cy + margin_y) / cam.fy;
}

// With cam.frustum as frustum_limits() set it (make_camera_params).
FLASHGS_HD void frustum_clamped_direction(const CameraParams& cam, float x_over_z, float y_over_z,
                                          float& tx, float& ty) {
  tx = clampf(x_over_z, cam.frustum[0], cam.frustum[1]);
  ty = clampf(y_over_z, cam.frustum[2], cam.frustum[3]);
}

// The culls that need only the view-space centre and the opacity, in project()'s order
// (kVisible: neither applies). The CUDA chunk cull classifies the Gaussians of a chunk that
// lies wholly outside the view with it, so its reasons are exactly project()'s.
FLASHGS_HD CullReason cull_by_centre(const GeometryParams& geo, const float view[3], float opacity) {
  if (!(view[2] > kNearZ)) return is_finite(view[2]) ? kCulledNear : kCulledDegenerate;
  // alpha = o exp(-q / 2) >= tau  <=>  q <= 2 ln(o / tau). Culled only when o < tau: the
  // blend keeps alpha == 1/255 (it skips alpha < 1/255), so o == tau still draws its centre
  // pixel (threshold 0); culling it too dropped 1/255 of colour there (stress opacity_edges).
  if (geo.opacity_radius && !(opacity >= geo.tau)) return kCulledLowOpacity;
  return kVisible;
}

// Projects one Gaussian. The 2D covariance is M M^T with M = J W R S (2x3). Its determinant
// comes from Cauchy-Binet as a sum of squared 2x2 minors of M, never as a*c - b*b: for a
// needle or pancake (scale ratios of 1e6 and more) a*c and b*b agree in every float digit
// and their difference is noise, often negative. The dilated determinant
// det + e (a + c) + e^2 (e = geo.dilation) is then a sum of positive terms, so the conic stays finite and
// positive definite for any finite input.
FLASHGS_HD CullReason project(const CameraParams& cam, const GeometryParams& geo,
                              const float position[3], const float scale[3],
                              const float quaternion[4], float opacity, Footprint& out) {
  float v[3];
  to_view(cam, position, v);
  const CullReason by_centre = cull_by_centre(geo, v, opacity);
  if (by_centre != kVisible) return by_centre;

  const float inv_z = 1.0f / v[2];
  const float mean_x = cam.fx * v[0] * inv_z + cam.cx;
  const float mean_y = cam.fy * v[1] * inv_z + cam.cy;
  // J W: rows of the projection Jacobian times the world-to-camera rotation. The Jacobian is
  // taken at the centre's direction clamped to the frustum widened by 30% (3DGS, which the
  // scenes were trained with): far outside the view the linearisation stretches a Gaussian
  // into a long smear across the image that the trained model never showed.
  float tx, ty;
  frustum_clamped_direction(cam, v[0] * inv_z, v[1] * inv_z, tx, ty);
  const float j00 = cam.fx * inv_z, j02 = -cam.fx * tx * inv_z;
  const float j11 = cam.fy * inv_z, j12 = -cam.fy * ty * inv_z;
  float t0[3], t1[3];
  for (int k = 0; k < 3; ++k) {
    t0[k] = j00 * cam.rotation[k] + j02 * cam.rotation[6 + k];
    t1[k] = j11 * cam.rotation[3 + k] + j12 * cam.rotation[6 + k];
  }
  float r[9];
  quaternion_to_matrix(quaternion, r);
  // M = (J W) R S: column k is (J W) times the k-th rotated axis scaled by s_k.
  float m0[3], m1[3];
  for (int k = 0; k < 3; ++k) {
    const float ax = r[k] * scale[k], ay = r[3 + k] * scale[k], az = r[6 + k] * scale[k];
    m0[k] = t0[0] * ax + t0[1] * ay + t0[2] * az;
    m1[k] = t1[0] * ax + t1[1] * ay + t1[2] * az;
  }
  const float a = m0[0] * m0[0] + m0[1] * m0[1] + m0[2] * m0[2];
  const float b = m0[0] * m1[0] + m0[1] * m1[1] + m0[2] * m1[2];
  const float c = m1[0] * m1[0] + m1[1] * m1[1] + m1[2] * m1[2];
  const float minor01 = m0[0] * m1[1] - m0[1] * m1[0];
  const float minor02 = m0[0] * m1[2] - m0[2] * m1[0];
  const float minor12 = m0[1] * m1[2] - m0[2] * m1[1];
  const float det = minor01 * minor01 + minor02 * minor02 + minor12 * minor12;

  const float dilation = geo.dilation;
  const float ad = a + dilation, cd = c + dilation;
  const float det_d = det + dilation * (a + c) + dilation * dilation;
  if (!is_finite(mean_x) || !is_finite(mean_y) || !is_finite(ad) || !is_finite(cd) ||
      !is_finite(b) || !is_finite(det_d) || !(det_d > 0.0f))
    return kCulledDegenerate;
  // The anti-aliased kernel keeps the Gaussian's integral: opacity * sqrt(det / det_d), both
  // determinants sums of non-negative terms (a needle's compensation stays accurate).
  const float drawn_opacity = geo.compensate_opacity ? opacity * sqrtf(det / det_d) : opacity;
  // alpha = o e^(-q/2) >= tau <=> q <= 2 ln(o / tau), with the opacity the blend uses. A
  // compensated opacity below tau is culled below, after the off-screen test, which then sees
  // the raw opacity's extent (>= 0: cull_by_centre passed it): the CUDA chunk cull bounds
  // that extent, so both name the same reason for every Gaussian.
  float threshold = kBaselineSigmas * kBaselineSigmas;
  if (geo.opacity_radius) threshold = 2.0f * portable_log((drawn_opacity >= geo.tau ? drawn_opacity : opacity) / geo.tau);
  // Eigen-decomposition of the dilated covariance [ad b; b cd], each step free of
  // cancellation: the largest eigenvalue as mid + root (a sum of non-negative terms), the
  // smallest as det / lambda_max (Vieta) rather than mid - root, which for a needle is the
  // difference of two numbers equal to every float digit; the major axis from whichever of
  // (lambda_max - cd, b) and (b, lambda_max - ad) adds, not subtracts.
  const float half_diff = 0.5f * (ad - cd);
  const float spread = half_diff * half_diff + b * b;  // mid^2 - det, without the cancellation
  const float root = sqrtf(spread);
  const float lambda_max = 0.5f * (ad + cd) + root;
  const float lambda_min = det_d / lambda_max;
  float ux = half_diff >= 0.0f ? half_diff + root : b;
  float uy = half_diff >= 0.0f ? b : root - half_diff;
  const float u_len = sqrtf(ux * ux + uy * uy);
  if (!is_finite(lambda_max) || !is_finite(u_len) || !(lambda_min > 0.0f)) return kCulledDegenerate;
  if (u_len > 0.0f) {
    ux = ux / u_len;
    uy = uy / u_len;
  } else {  // isotropic: any axis
    ux = 1.0f;
    uy = 0.0f;
  }
  const float s_major = 1.0f / sqrtf(lambda_max), s_minor = 1.0f / sqrtf(lambda_min);
  const float w0 = ux * s_major, w1 = uy * s_major, w2 = -uy * s_minor, w3 = ux * s_minor;

  float half_x, half_y;
  if (geo.tight_bbox) {
    // max |dx| on q = t is sqrt(t * Sigma_xx) (same for y)
    half_x = sqrtf(threshold * ad);
    half_y = sqrtf(threshold * cd);
  } else if (geo.baseline) {
    // 3DGS's radius: ceil(3 sqrt(mid + sqrt(max(0.1, mid^2 - det)))). The 0.1 floor is part
    // of the rule the scenes were trained with: it widens near-isotropic footprints (the
    // smallest gets radius 3, not 2), and getRect below cuts pixels up to 1 px inside it.
    const float lambda_box = 0.5f * (ad + cd) + sqrtf(maxf(kBaselineSpreadFloor, spread));
    half_x = half_y = ceilf(sqrtf(threshold * lambda_box));
  } else {
    half_x = half_y = sqrtf(threshold * lambda_max);
  }
  if (!is_finite(half_x) || !is_finite(half_y)) return kCulledDegenerate;

  const float tiles_x = static_cast<float>(cam.tiles_x), tiles_y = static_cast<float>(cam.tiles_y);
  const float ts = static_cast<float>(kTileSize);
  if (geo.baseline) {
    // 3DGS getRect: [trunc((m - r) / 16), trunc((m + r + 15) / 16)), clamped to the grid.
    // Clamped in float first: a huge radius must not overflow the int conversion.
    out.tile_x0 = static_cast<int>(clampf((mean_x - half_x) / ts, 0.0f, tiles_x));
    out.tile_x1 = static_cast<int>(clampf((mean_x + half_x + ts - 1.0f) / ts, 0.0f, tiles_x));
    out.tile_y0 = static_cast<int>(clampf((mean_y - half_y) / ts, 0.0f, tiles_y));
    out.tile_y1 = static_cast<int>(clampf((mean_y + half_y + ts - 1.0f) / ts, 0.0f, tiles_y));
  } else {
    // Exactly the tiles holding a pixel centre within the box.
    const float px0 = maxf(ceilf(mean_x - half_x), 0.0f);
    const float px1 = minf(floorf(mean_x + half_x), static_cast<float>(cam.width - 1));
    const float py0 = maxf(ceilf(mean_y - half_y), 0.0f);
    const float py1 = minf(floorf(mean_y + half_y), static_cast<float>(cam.height - 1));
    if (!(px0 <= px1) || !(py0 <= py1)) return kCulledOffscreen;
    out.tile_x0 = static_cast<int>(px0) / kTileSize;
    out.tile_x1 = static_cast<int>(px1) / kTileSize + 1;
    out.tile_y0 = static_cast<int>(py0) / kTileSize;
    out.tile_y1 = static_cast<int>(py1) / kTileSize + 1;
  }
  if (out.tile_x0 >= out.tile_x1 || out.tile_y0 >= out.tile_y1) return kCulledOffscreen;
  if (geo.opacity_radius && !(drawn_opacity >= geo.tau)) return kCulledLowOpacity;

  out.mean_x = mean_x;
  out.opacity = drawn_opacity;
  out.mean_y = mean_y;
  out.depth = v[2];
  // The conic from the whitened rows (W^T W): consistent with them, and free of det_d,
  // which overflows (sigma^4) long before the entries do.
  out.conic_a = w0 * w0 + w2 * w2;
  out.conic_b = w0 * w1 + w2 * w3;
  out.conic_c = w1 * w1 + w3 * w3;
  out.whiten[0] = w0;
  out.whiten[1] = w1;
  out.whiten[2] = w2;
  out.whiten[3] = w3;
  out.edge_slope_x = -out.conic_b / out.conic_c;
  out.edge_slope_y = -out.conic_b / out.conic_a;
  out.threshold = threshold;
  return kVisible;
}

// a b + c, rounded twice: the tile decisions that the host and the GPU must make alike. FUSED,
// on the GPU, rounds once: for tests whose margin covers the difference (the blend's region
// test), at fewer instructions.
template <bool FUSED = false>
FLASHGS_HD float mul_add(float a, float b, float c) {
#ifdef __CUDA_ARCH__
  if constexpr (FUSED) return __fmaf_rn(a, b, c);
#endif
  return a * b + c;
}

// q at offset (dx, dy) from the whitened rows w (see Footprint::whiten).
template <bool FUSED = false>
FLASHGS_HD float whitened_q(const float w[4], float dx, float dy) {
  const float u = mul_add<FUSED>(w[0], dx, w[1] * dy);
  const float v = mul_add<FUSED>(w[2], dx, w[3] * dy);
  return mul_add<FUSED>(u, u, v * v);
}

// The minimum of q over the rectangle [dx0, dx1] x [dy0, dy1] of offsets from the centre, and
// whether the ellipse q(d) <= t meets that rectangle. FlashGS's exact test without square
// roots: if the centre is outside, the minimum of the convex q over the rectangle lies on an
// edge facing the centre, and along such an edge q is a parabola whose minimiser is edge_slope
// times the edge's offset, clamped to the edge. The minimiser along an edge comes from the
// conic W^T W, where a small error only moves it along a flat valley (q changes to second
// order); q itself is evaluated in the whitened form, without cancellation, so that tiles
// thousands of pixels along a needle are decided correctly.
// Written without branches (it runs for every lane of a warp at once): each axis's nearest
// offset is 0 where the rectangle spans the centre, so the two edge points below are always
// points of the rectangle, one of them its minimum (the centre itself when it is inside).
// Offsets must be finite (they are for every visible footprint).
template <bool FUSED = false>
FLASHGS_HD float whitened_q_min_on_rect(const float w[4], float edge_slope_x, float edge_slope_y, float dx0,
                                       float dx1, float dy0, float dy1) {
  const float near_x = clampf(0.0f, dx0, dx1), near_y = clampf(0.0f, dy0, dy1);
  const float q_on_x_edge = whitened_q<FUSED>(w, near_x, clampf(edge_slope_x * near_x, dy0, dy1));
  const float q_on_y_edge = whitened_q<FUSED>(w, clampf(edge_slope_y * near_y, dx0, dx1), near_y);
  return minf(q_on_x_edge, q_on_y_edge);
}

FLASHGS_HD bool whitened_ellipse_meets_rect(const float w[4], float edge_slope_x, float edge_slope_y, float t,
                                            float dx0, float dx1, float dy0, float dy1) {
  return whitened_q_min_on_rect(w, edge_slope_x, edge_slope_y, dx0, dx1, dy0, dy1) <= t;
}

// The exact test for tile (tx, ty): the rectangle spanned by its pixel centres, clipped to
// the image. The parts of a Footprint it reads are passed one by one for callers that keep
// only those.
FLASHGS_HD bool ellipse_touches_tile(const float whiten[4], float edge_slope_x, float edge_slope_y, float threshold,
                                     float mean_x, float mean_y, int tx, int ty, int width, int height) {
  const float x0 = static_cast<float>(tx * kTileSize);
  const float y0 = static_cast<float>(ty * kTileSize);
  const float x1 = minf(x0 + (kTileSize - 1), static_cast<float>(width - 1));
  const float y1 = minf(y0 + (kTileSize - 1), static_cast<float>(height - 1));
  return whitened_ellipse_meets_rect(whiten, edge_slope_x, edge_slope_y, threshold, x0 - mean_x, x1 - mean_x,
                                     y0 - mean_y, y1 - mean_y);
}

FLASHGS_HD bool footprint_touches_tile(const Footprint& f, int tx, int ty, int width, int height) {
  return ellipse_touches_tile(f.whiten, f.edge_slope_x, f.edge_slope_y, f.threshold, f.mean_x, f.mean_y, tx, ty,
                              width, height);
}

// Real spherical harmonics constants (degree 0..3) of the 3DGS colour model, in float.
constexpr float kShC0 = static_cast<float>(model::kShC0);
constexpr float kShC1 = static_cast<float>(model::kShC1);
// Scalars, not arrays: a namespace-scope constexpr array cannot be read in CUDA device code.
constexpr float kShC2_0 = static_cast<float>(model::kShC2_0);
constexpr float kShC2_1 = static_cast<float>(model::kShC2_1);
constexpr float kShC2_2 = static_cast<float>(model::kShC2_2);
constexpr float kShC2_3 = static_cast<float>(model::kShC2_3);
constexpr float kShC2_4 = static_cast<float>(model::kShC2_4);
constexpr float kShC3_0 = static_cast<float>(model::kShC3_0);
constexpr float kShC3_1 = static_cast<float>(model::kShC3_1);
constexpr float kShC3_2 = static_cast<float>(model::kShC3_2);
constexpr float kShC3_3 = static_cast<float>(model::kShC3_3);
constexpr float kShC3_4 = static_cast<float>(model::kShC3_4);
constexpr float kShC3_5 = static_cast<float>(model::kShC3_5);
constexpr float kShC3_6 = static_cast<float>(model::kShC3_6);

// SH basis values for a unit direction, for bands 0..degree (DEGREE is a template argument so
// that a degree-0 scene compiles to no SH work at all).
template <int DEGREE>
FLASHGS_HD void sh_basis(float x, float y, float z, float basis[16]) {
  basis[0] = kShC0;
  if (DEGREE > 0) {
    basis[1] = -kShC1 * y;
    basis[2] = kShC1 * z;
    basis[3] = -kShC1 * x;
  }
  if (DEGREE > 1) {
    const float xx = x * x, yy = y * y, zz = z * z;
    basis[4] = kShC2_0 * x * y;
    basis[5] = kShC2_1 * y * z;
    basis[6] = kShC2_2 * (2.0f * zz - xx - yy);
    basis[7] = kShC2_3 * x * z;
    basis[8] = kShC2_4 * (xx - yy);
    if (DEGREE > 2) {
      basis[9] = kShC3_0 * y * (3.0f * xx - yy);
      basis[10] = kShC3_1 * x * y * z;
      basis[11] = kShC3_2 * y * (4.0f * zz - xx - yy);
      basis[12] = kShC3_3 * z * (2.0f * zz - 3.0f * xx - 3.0f * yy);
      basis[13] = kShC3_4 * x * (4.0f * zz - xx - yy);
      basis[14] = kShC3_5 * z * (xx - yy);
      basis[15] = kShC3_6 * x * (xx - 3.0f * yy);
    }
  }
}

// RGB of one Gaussian seen from `camera_position`: SH + 0.5, clamped at 0 (3DGS).
// `rest` holds this Gaussian's coefficients 1..K-1 as [k][channel]; lower bands come first,
// so a scene with more bands than DEGREE is evaluated by reading only its first ones.
template <int DEGREE>
FLASHGS_HD void sh_to_rgb(const float camera_position[3], const float position[3],
                          const float dc[3], const float* rest, float rgb[3]) {
  float basis[16];
  float dx = position[0] - camera_position[0], dy = position[1] - camera_position[1],
        dz = position[2] - camera_position[2];
  if (DEGREE > 0) {
    const float len2 = dx * dx + dy * dy + dz * dz;
    const float inv = len2 > 0.0f ? 1.0f / sqrtf(len2) : 0.0f;
    dx *= inv;
    dy *= inv;
    dz *= inv;
  }
  sh_basis<DEGREE>(dx, dy, dz, basis);
  for (int ch = 0; ch < 3; ++ch) {
    float sum = basis[0] * dc[ch];
    for (int k = 1; k < (DEGREE + 1) * (DEGREE + 1); ++k) sum += basis[k] * rest[(k - 1) * 3 + ch];
    rgb[ch] = maxf(sum + 0.5f, 0.0f);
  }
}

// IEEE binary16 bits of v, rounded to nearest even, from integer operations only so that the
// host and the device encode bit for bit alike. Magnitudes above the half range clamp to
// +-65504 (the largest half) instead of becoming infinite; NaN never reaches here (the loaders
// reject non-finite values).
FLASHGS_HD std::uint16_t float_to_half_bits(float v) {
  std::uint32_t bits;
  std::memcpy(&bits, &v, 4);
  const std::uint32_t sign = (bits >> 16) & 0x8000u;
  const std::uint32_t magnitude = bits & 0x7fffffffu;
  if (magnitude >= 0x477fe000u) return static_cast<std::uint16_t>(sign | 0x7bffu);  // >= 65504
  if (magnitude >= 0x38800000u) {  // a normal half (>= 2^-14): drop 13 mantissa bits, ties to even
    const std::uint32_t rounded = magnitude + 0xfffu + ((magnitude >> 13) & 1u);
    return static_cast<std::uint16_t>(sign | ((rounded - 0x38000000u) >> 13));
  }
  // A half subnormal, m * 2^-24: the float's 24-bit significand shifted right, ties to even
  // (a carry into bit 10 is the smallest normal half, as the encoding wants).
  const std::uint32_t exponent = magnitude >> 23;
  const std::uint32_t shift = 126u - exponent;  // 14 at 2^-15, 24 at 2^-25
  if (exponent == 0u || shift > 24u) return static_cast<std::uint16_t>(sign);  // below half of 2^-24
  const std::uint32_t significand = (magnitude & 0x7fffffu) | 0x800000u;
  std::uint32_t q = significand >> shift;
  const std::uint32_t rest = significand & ((1u << shift) - 1u), tie = 1u << (shift - 1u);
  if (rest > tie || (rest == tie && (q & 1u))) ++q;
  return static_cast<std::uint16_t>(sign | q);
}

// The float a binary16 value stands for (exact: every half is a float).
FLASHGS_HD float half_bits_to_float(std::uint16_t h) {
  const std::uint32_t sign = static_cast<std::uint32_t>(h & 0x8000u) << 16;
  const std::uint32_t exponent = (h >> 10) & 0x1fu, mantissa = h & 0x3ffu;
  std::uint32_t bits;
  if (exponent == 0u) {
    float magnitude = static_cast<float>(mantissa) * 5.9604644775390625e-8f;  // m * 2^-24, exact
    std::memcpy(&bits, &magnitude, 4);
    bits |= sign;
  } else if (exponent == 31u) {
    bits = sign | 0x7f800000u | (mantissa << 13);
  } else {
    bits = sign | ((exponent + 112u) << 23) | (mantissa << 13);
  }
  float out;
  std::memcpy(&out, &bits, 4);
  return out;
}

// v as the nearest half value (RenderOptions::fp16_sh), as a float.
FLASHGS_HD float round_to_half(float v) { return half_bits_to_float(float_to_half_bits(v)); }

// Sort key part for a depth: positive floats order like their bit patterns.
FLASHGS_HD std::uint32_t depth_bits(float depth) {
  std::uint32_t bits;
  std::memcpy(&bits, &depth, 4);
  return bits;
}

}  // namespace gm
}  // namespace flashgs
