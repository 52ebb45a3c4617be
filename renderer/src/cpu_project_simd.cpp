// CPU project stage, SIMD kernel: gm::project and the BlendGaussian fill on a vector of
// Gaussians at a time (Google Highway, compiled for every x86 target, dispatched at run time).
//
// It gives the scalar reference's bytes (tests/test_cpu_project_simd.cpp): gm::project uses only
// correctly rounded operations (+ - * / sqrt floor ceil, comparisons, portable_log's bit
// operations), so each is done per lane in the scalar code's order: a Mul then an Add, never a
// MulAdd (this file is compiled with -ffp-contract=off like the rest of the library), and
// min / max / clamp as the scalar ternaries (which operand wins on a tie or a NaN). Branches are
// masks: a lane keeps the first cull reason in gm::project's order; culled lanes compute
// values nobody reads and write no footprint.
#include <algorithm>
#include <cmath>

#include "cpu_frame.h"

#ifdef FLASHGS_HAVE_HWY
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "cpu_project_simd.cpp"
#include <hwy/foreach_target.h>  // re-includes this file once per target
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace flashgs {
namespace cpu {
namespace HWY_NAMESPACE {

#if HWY_TARGET == HWY_SCALAR
// One lane is the scalar code.
void ProjectBlock(const SceneArrays& scene, int degree, Frame& frame,
                  std::int64_t begin, std::int64_t end) {
  project_block_scalar(scene, degree, frame, begin, end);
}
#else
namespace hn = hwy::HWY_NAMESPACE;

using FloatTag = hn::ScalableTag<float>;
using IntTag = hn::RebindToSigned<FloatTag>;
using FloatVec = hn::Vec<FloatTag>;
using IntVec = hn::Vec<IntTag>;
using FloatMask = hn::Mask<FloatTag>;

// gm::clampf, minf, maxf: the same operand wins on ties and NaN as in the ternaries.
HWY_INLINE FloatVec clamp(FloatVec v, FloatVec lo, FloatVec hi) {
  return hn::IfThenElse(hn::Lt(v, lo), lo, hn::IfThenElse(hn::Gt(v, hi), hi, v));
}
HWY_INLINE FloatVec min_as_scalar(FloatVec a, FloatVec b) { return hn::IfThenElse(hn::Lt(a, b), a, b); }
HWY_INLINE FloatVec max_as_scalar(FloatVec a, FloatVec b) { return hn::IfThenElse(hn::Gt(a, b), a, b); }

// gm::is_finite: the exponent field is not all ones.
HWY_INLINE FloatMask is_finite(FloatVec v) {
  const FloatTag d;
  const IntTag di;
  const IntVec exponent_mask = hn::Set(di, 0x7f800000);
  return hn::RebindMask(d, hn::Ne(hn::And(hn::BitCast(di, v), exponent_mask), exponent_mask));
}

// gm::portable_log per lane.
HWY_INLINE FloatVec portable_log(FloatVec x) {
  const FloatTag d;
  const IntTag di;
  const IntVec exponent_field = hn::Set(di, 0xff);
  IntVec bits = hn::BitCast(di, x);
  IntVec exponent = hn::Sub(hn::And(hn::ShiftRight<23>(bits), exponent_field), hn::Set(di, 127));
  const auto subnormal = hn::Eq(exponent, hn::Set(di, -127));
  const IntVec scaled_bits = hn::BitCast(di, hn::Mul(x, hn::Set(d, 8388608.0f)));
  const IntVec scaled_exponent = hn::Sub(
      hn::Sub(hn::And(hn::ShiftRight<23>(scaled_bits), exponent_field), hn::Set(di, 127)), hn::Set(di, 23));
  bits = hn::IfThenElse(subnormal, scaled_bits, bits);
  exponent = hn::IfThenElse(subnormal, scaled_exponent, exponent);
  FloatVec m = hn::BitCast(d, hn::Or(hn::And(bits, hn::Set(di, 0x007fffff)), hn::Set(di, 0x3f800000)));
  const FloatMask above = hn::Gt(m, hn::Set(d, 1.41421356f));
  m = hn::IfThenElse(above, hn::Mul(m, hn::Set(d, 0.5f)), m);
  exponent = hn::IfThenElse(hn::RebindMask(di, above), hn::Add(exponent, hn::Set(di, 1)), exponent);
  const FloatVec one = hn::Set(d, 1.0f);
  const FloatVec s = hn::Div(hn::Sub(m, one), hn::Add(m, one));
  const FloatVec s2 = hn::Mul(s, s);
  FloatVec series = hn::Mul(s2, hn::Set(d, 0.222222222f));
  series = hn::Mul(s2, hn::Add(hn::Set(d, 0.285714286f), series));
  series = hn::Mul(s2, hn::Add(hn::Set(d, 0.4f), series));
  series = hn::Mul(s2, hn::Add(hn::Set(d, 0.666666667f), series));
  series = hn::Mul(s, hn::Add(hn::Set(d, 2.0f), series));
  const FloatVec log = hn::Add(hn::Mul(hn::ConvertTo(d, exponent), hn::Set(d, 0.693147181f)), series);
  return hn::IfThenElse(hn::Gt(x, hn::Zero(d)), log, hn::Set(d, -INFINITY));
}

// a0 b0 + a1 b1 + a2 b2, left to right.
HWY_INLINE FloatVec dot3(FloatVec a0, FloatVec a1, FloatVec a2, FloatVec b0, FloatVec b1, FloatVec b2) {
  return hn::Add(hn::Add(hn::Mul(a0, b0), hn::Mul(a1, b1)), hn::Mul(a2, b2));
}

// One vector's results, lane by lane, for the stores into Frame's AoS arrays.
struct Lanes {
  static constexpr std::size_t kMax = HWY_MAX_BYTES / sizeof(float);
  HWY_ALIGN std::int32_t reason[kMax];
  HWY_ALIGN std::int32_t tile_x0[kMax], tile_y0[kMax], tile_x1[kMax], tile_y1[kMax];
  HWY_ALIGN float mean_x[kMax], mean_y[kMax], depth[kMax], threshold[kMax], opacity[kMax];
  HWY_ALIGN float conic_a[kMax], conic_b[kMax], conic_c[kMax];
  HWY_ALIGN float w0[kMax], w1[kMax], w2[kMax], w3[kMax];
  HWY_ALIGN float edge_slope_x[kMax], edge_slope_y[kMax];
  HWY_ALIGN float sh_basis[16][kMax];  // gm::sh_basis, per lane
};

// A lane's cull reason: the first one that applies, as in gm::project's early returns.
class CullReasons {
 public:
  CullReasons() : m_reason(hn::Zero(IntTag())), m_open(hn::FirstN(IntTag(), hn::Lanes(IntTag()))) {}
  void cull_where(FloatMask culled, gm::CullReason reason) {
    const auto newly = hn::And(m_open, hn::RebindMask(IntTag(), culled));
    m_reason = hn::IfThenElse(newly, hn::Set(IntTag(), reason), m_reason);
    m_open = hn::AndNot(newly, m_open);
  }
  void cull_where(hn::Mask<IntTag> culled, gm::CullReason reason) {
    cull_where(hn::RebindMask(FloatTag(), culled), reason);
  }
  bool none_left() const { return hn::AllFalse(IntTag(), m_open); }
  IntVec reasons() const { return m_reason; }

 private:
  IntVec m_reason;
  hn::Mask<IntTag> m_open;  // lanes not culled yet
};

// gm::project for the lanes of Gaussians [i, i + lanes); fills `out`, returns false when every
// lane is culled (out.reason alone is then set).
template <bool kOpacityRadius, bool kTightBox, bool kBaseline>
bool project_vector(const SceneArrays& scene, const Frame& frame, std::int64_t i, Lanes& out) {
  const FloatTag d;
  const IntTag di;
  const gm::CameraParams& cam = frame.camera;
  const float* rot = cam.rotation;
  FloatVec px, py, pz;
  hn::LoadInterleaved3(d, &scene.positions[i * 3], px, py, pz);
  // gm::to_view
  const FloatVec d0 = hn::Sub(px, hn::Set(d, cam.position[0]));
  const FloatVec d1 = hn::Sub(py, hn::Set(d, cam.position[1]));
  const FloatVec d2 = hn::Sub(pz, hn::Set(d, cam.position[2]));
  const FloatVec v0 = dot3(hn::Set(d, rot[0]), hn::Set(d, rot[1]), hn::Set(d, rot[2]), d0, d1, d2);
  const FloatVec v1 = dot3(hn::Set(d, rot[3]), hn::Set(d, rot[4]), hn::Set(d, rot[5]), d0, d1, d2);
  const FloatVec v2 = dot3(hn::Set(d, rot[6]), hn::Set(d, rot[7]), hn::Set(d, rot[8]), d0, d1, d2);
  const FloatVec opacity = hn::LoadU(d, &scene.opacities[i]);

  // gm::cull_by_centre
  CullReasons cull;
  const FloatMask finite_z = is_finite(v2);
  const FloatMask behind = hn::Not(hn::Gt(v2, hn::Set(d, gm::kNearZ)));
  cull.cull_where(hn::And(behind, finite_z), gm::kCulledNear);
  cull.cull_where(hn::AndNot(finite_z, behind), gm::kCulledDegenerate);
  if (kOpacityRadius) cull.cull_where(hn::Not(hn::Ge(opacity, hn::Set(d, frame.geometry.tau))), gm::kCulledLowOpacity);
  if (cull.none_left()) {
    hn::Store(cull.reasons(), di, out.reason);
    return false;
  }

  const FloatVec inv_z = hn::Div(hn::Set(d, 1.0f), v2);
  const FloatVec fx = hn::Set(d, cam.fx), fy = hn::Set(d, cam.fy);
  const FloatVec mean_x = hn::Add(hn::Mul(hn::Mul(fx, v0), inv_z), hn::Set(d, cam.cx));
  const FloatVec mean_y = hn::Add(hn::Mul(hn::Mul(fy, v1), inv_z), hn::Set(d, cam.cy));
  const FloatVec tx = clamp(hn::Mul(v0, inv_z), hn::Set(d, cam.frustum[0]), hn::Set(d, cam.frustum[1]));
  const FloatVec ty = clamp(hn::Mul(v1, inv_z), hn::Set(d, cam.frustum[2]), hn::Set(d, cam.frustum[3]));
  const FloatVec j00 = hn::Mul(fx, inv_z), j02 = hn::Mul(hn::Mul(hn::Set(d, -cam.fx), tx), inv_z);
  const FloatVec j11 = hn::Mul(fy, inv_z), j12 = hn::Mul(hn::Mul(hn::Set(d, -cam.fy), ty), inv_z);
  FloatVec t0[3], t1[3];
  for (int k = 0; k < 3; ++k) {
    t0[k] = hn::Add(hn::Mul(j00, hn::Set(d, rot[k])), hn::Mul(j02, hn::Set(d, rot[6 + k])));
    t1[k] = hn::Add(hn::Mul(j11, hn::Set(d, rot[3 + k])), hn::Mul(j12, hn::Set(d, rot[6 + k])));
  }
  // gm::quaternion_to_matrix
  FloatVec qw, qx, qy, qz;
  hn::LoadInterleaved4(d, &scene.rotations[i * 4], qw, qx, qy, qz);
  const FloatVec one = hn::Set(d, 1.0f), two = hn::Set(d, 2.0f);
  FloatVec r[9];
  r[0] = hn::Sub(one, hn::Mul(two, hn::Add(hn::Mul(qy, qy), hn::Mul(qz, qz))));
  r[1] = hn::Mul(two, hn::Sub(hn::Mul(qx, qy), hn::Mul(qw, qz)));
  r[2] = hn::Mul(two, hn::Add(hn::Mul(qx, qz), hn::Mul(qw, qy)));
  r[3] = hn::Mul(two, hn::Add(hn::Mul(qx, qy), hn::Mul(qw, qz)));
  r[4] = hn::Sub(one, hn::Mul(two, hn::Add(hn::Mul(qx, qx), hn::Mul(qz, qz))));
  r[5] = hn::Mul(two, hn::Sub(hn::Mul(qy, qz), hn::Mul(qw, qx)));
  r[6] = hn::Mul(two, hn::Sub(hn::Mul(qx, qz), hn::Mul(qw, qy)));
  r[7] = hn::Mul(two, hn::Add(hn::Mul(qy, qz), hn::Mul(qw, qx)));
  r[8] = hn::Sub(one, hn::Mul(two, hn::Add(hn::Mul(qx, qx), hn::Mul(qy, qy))));
  FloatVec s[3];
  hn::LoadInterleaved3(d, &scene.scales[i * 3], s[0], s[1], s[2]);
  FloatVec m0[3], m1[3];
  for (int k = 0; k < 3; ++k) {
    const FloatVec ax = hn::Mul(r[k], s[k]), ay = hn::Mul(r[3 + k], s[k]), az = hn::Mul(r[6 + k], s[k]);
    m0[k] = dot3(t0[0], t0[1], t0[2], ax, ay, az);
    m1[k] = dot3(t1[0], t1[1], t1[2], ax, ay, az);
  }
  const FloatVec a = dot3(m0[0], m0[1], m0[2], m0[0], m0[1], m0[2]);
  const FloatVec b = dot3(m0[0], m0[1], m0[2], m1[0], m1[1], m1[2]);
  const FloatVec c = dot3(m1[0], m1[1], m1[2], m1[0], m1[1], m1[2]);
  const FloatVec minor01 = hn::Sub(hn::Mul(m0[0], m1[1]), hn::Mul(m0[1], m1[0]));
  const FloatVec minor02 = hn::Sub(hn::Mul(m0[0], m1[2]), hn::Mul(m0[2], m1[0]));
  const FloatVec minor12 = hn::Sub(hn::Mul(m0[1], m1[2]), hn::Mul(m0[2], m1[1]));
  const FloatVec det = dot3(minor01, minor02, minor12, minor01, minor02, minor12);

  const gm::GeometryParams& geo = frame.geometry;
  const FloatVec dilation = hn::Set(d, geo.dilation), zero = hn::Zero(d), half = hn::Set(d, 0.5f);
  const FloatVec ad = hn::Add(a, dilation), cd = hn::Add(c, dilation);
  const FloatVec det_d =
      hn::Add(hn::Add(det, hn::Mul(dilation, hn::Add(a, c))), hn::Set(d, geo.dilation * geo.dilation));
  const FloatMask well_formed = hn::And(
      hn::And(hn::And(is_finite(mean_x), is_finite(mean_y)), hn::And(is_finite(ad), is_finite(cd))),
      hn::And(hn::And(is_finite(b), is_finite(det_d)), hn::Gt(det_d, zero)));
  cull.cull_where(hn::Not(well_formed), gm::kCulledDegenerate);
  // gm::project's drawn opacity and extent (the raw opacity's where the drawn one is below tau).
  const FloatVec tau = hn::Set(d, geo.tau);
  const FloatVec drawn_opacity =
      geo.compensate_opacity ? hn::Mul(opacity, hn::Sqrt(hn::Div(det, det_d))) : opacity;
  const FloatMask drawn_visible = hn::Ge(drawn_opacity, tau);
  const FloatVec threshold =
      kOpacityRadius
          ? hn::Mul(hn::Set(d, 2.0f), portable_log(hn::Div(hn::IfThenElse(drawn_visible, drawn_opacity, opacity), tau)))
          : hn::Set(d, gm::kBaselineSigmas * gm::kBaselineSigmas);
  // The eigen-decomposition (see gm::project).
  const FloatVec half_diff = hn::Mul(half, hn::Sub(ad, cd));
  const FloatVec spread = hn::Add(hn::Mul(half_diff, half_diff), hn::Mul(b, b));
  const FloatVec root = hn::Sqrt(spread);
  const FloatVec mid = hn::Mul(half, hn::Add(ad, cd));
  const FloatVec lambda_max = hn::Add(mid, root);
  const FloatVec lambda_min = hn::Div(det_d, lambda_max);
  const FloatMask diff_positive = hn::Ge(half_diff, zero);
  FloatVec ux = hn::IfThenElse(diff_positive, hn::Add(half_diff, root), b);
  FloatVec uy = hn::IfThenElse(diff_positive, b, hn::Sub(root, half_diff));
  const FloatVec u_len = hn::Sqrt(hn::Add(hn::Mul(ux, ux), hn::Mul(uy, uy)));
  cull.cull_where(hn::Not(hn::And(hn::And(is_finite(lambda_max), is_finite(u_len)), hn::Gt(lambda_min, zero))),
                  gm::kCulledDegenerate);
  const FloatMask has_axis = hn::Gt(u_len, zero);
  ux = hn::IfThenElse(has_axis, hn::Div(ux, u_len), one);
  uy = hn::IfThenElse(has_axis, hn::Div(uy, u_len), zero);
  const FloatVec s_major = hn::Div(one, hn::Sqrt(lambda_max)), s_minor = hn::Div(one, hn::Sqrt(lambda_min));
  const FloatVec w0 = hn::Mul(ux, s_major), w1 = hn::Mul(uy, s_major);
  const FloatVec w2 = hn::Mul(hn::Neg(uy), s_minor), w3 = hn::Mul(ux, s_minor);

  FloatVec half_x, half_y;
  if (kTightBox) {
    half_x = hn::Sqrt(hn::Mul(threshold, ad));
    half_y = hn::Sqrt(hn::Mul(threshold, cd));
  } else if (kBaseline) {
    const FloatVec lambda_box = hn::Add(mid, hn::Sqrt(max_as_scalar(hn::Set(d, gm::kBaselineSpreadFloor), spread)));
    half_x = half_y = hn::Ceil(hn::Sqrt(hn::Mul(threshold, lambda_box)));
  } else {
    half_x = half_y = hn::Sqrt(hn::Mul(threshold, lambda_max));
  }
  cull.cull_where(hn::Not(hn::And(is_finite(half_x), is_finite(half_y))), gm::kCulledDegenerate);

  IntVec tile_x0, tile_x1, tile_y0, tile_y1;
  const FloatVec ts = hn::Set(d, static_cast<float>(gm::kTileSize));
  if (kBaseline) {
    // 3DGS getRect, as gm::project: clamped in float, then truncated.
    const FloatVec tiles_x = hn::Set(d, static_cast<float>(cam.tiles_x));
    const FloatVec tiles_y = hn::Set(d, static_cast<float>(cam.tiles_y));
    auto tile_of = [&](FloatVec edge, FloatVec tiles) {
      return hn::ConvertTo(di, clamp(hn::Div(edge, ts), zero, tiles));
    };
    tile_x0 = tile_of(hn::Sub(mean_x, half_x), tiles_x);
    tile_x1 = tile_of(hn::Sub(hn::Add(hn::Add(mean_x, half_x), ts), one), tiles_x);
    tile_y0 = tile_of(hn::Sub(mean_y, half_y), tiles_y);
    tile_y1 = tile_of(hn::Sub(hn::Add(hn::Add(mean_y, half_y), ts), one), tiles_y);
  } else {
    const FloatVec px0 = max_as_scalar(hn::Ceil(hn::Sub(mean_x, half_x)), zero);
    const FloatVec last_x = hn::Set(d, static_cast<float>(cam.width - 1));
    const FloatVec last_y = hn::Set(d, static_cast<float>(cam.height - 1));
    const FloatVec px1 = min_as_scalar(hn::Floor(hn::Add(mean_x, half_x)), last_x);
    const FloatVec py0 = max_as_scalar(hn::Ceil(hn::Sub(mean_y, half_y)), zero);
    const FloatVec py1 = min_as_scalar(hn::Floor(hn::Add(mean_y, half_y)), last_y);
    cull.cull_where(hn::Not(hn::And(hn::Le(px0, px1), hn::Le(py0, py1))), gm::kCulledOffscreen);
    // Pixel indices >= 0 on every lane still open: / kTileSize is a shift.
    static_assert(gm::kTileSize == 16, "the shifts below divide by 16");
    const IntVec one_tile = hn::Set(di, 1);
    tile_x0 = hn::ShiftRight<4>(hn::ConvertTo(di, px0));
    tile_x1 = hn::Add(hn::ShiftRight<4>(hn::ConvertTo(di, px1)), one_tile);
    tile_y0 = hn::ShiftRight<4>(hn::ConvertTo(di, py0));
    tile_y1 = hn::Add(hn::ShiftRight<4>(hn::ConvertTo(di, py1)), one_tile);
  }
  cull.cull_where(hn::Not(hn::And(hn::Lt(tile_x0, tile_x1), hn::Lt(tile_y0, tile_y1))), gm::kCulledOffscreen);
  if (kOpacityRadius) cull.cull_where(hn::Not(drawn_visible), gm::kCulledLowOpacity);
  hn::Store(cull.reasons(), di, out.reason);
  if (cull.none_left()) return false;

  const FloatVec conic_a = hn::Add(hn::Mul(w0, w0), hn::Mul(w2, w2));
  const FloatVec conic_b = hn::Add(hn::Mul(w0, w1), hn::Mul(w2, w3));
  const FloatVec conic_c = hn::Add(hn::Mul(w1, w1), hn::Mul(w3, w3));
  hn::Store(tile_x0, di, out.tile_x0);
  hn::Store(tile_y0, di, out.tile_y0);
  hn::Store(tile_x1, di, out.tile_x1);
  hn::Store(tile_y1, di, out.tile_y1);
  hn::Store(mean_x, d, out.mean_x);
  hn::Store(mean_y, d, out.mean_y);
  hn::Store(v2, d, out.depth);
  hn::Store(threshold, d, out.threshold);
  hn::Store(drawn_opacity, d, out.opacity);
  hn::Store(conic_a, d, out.conic_a);
  hn::Store(conic_b, d, out.conic_b);
  hn::Store(conic_c, d, out.conic_c);
  hn::Store(w0, d, out.w0);
  hn::Store(w1, d, out.w1);
  hn::Store(w2, d, out.w2);
  hn::Store(w3, d, out.w3);
  hn::Store(hn::Div(hn::Neg(conic_b), conic_c), d, out.edge_slope_x);
  hn::Store(hn::Div(hn::Neg(conic_b), conic_a), d, out.edge_slope_y);
  return true;
}

// gm::sh_basis<DEGREE> for the lanes of Gaussians [i, i + lanes), the same expressions (and
// sh_to_rgb's normalised direction). The sums over the coefficients follow per visible lane.
template <int DEGREE>
void sh_basis_vector(const SceneArrays& scene, const Frame& frame, std::int64_t i, Lanes& out) {
  if (DEGREE == 0) return;  // basis[0] is a constant
  const FloatTag d;
  FloatVec basis[16];
  FloatVec x, y, z;
  hn::LoadInterleaved3(d, &scene.positions[i * 3], x, y, z);
  x = hn::Sub(x, hn::Set(d, frame.camera.position[0]));
  y = hn::Sub(y, hn::Set(d, frame.camera.position[1]));
  z = hn::Sub(z, hn::Set(d, frame.camera.position[2]));
  const FloatVec len2 = dot3(x, y, z, x, y, z);
  const FloatVec inv =
      hn::IfThenElse(hn::Gt(len2, hn::Zero(d)), hn::Div(hn::Set(d, 1.0f), hn::Sqrt(len2)), hn::Zero(d));
  x = hn::Mul(x, inv);
  y = hn::Mul(y, inv);
  z = hn::Mul(z, inv);
  basis[1] = hn::Mul(hn::Set(d, -gm::kShC1), y);
  basis[2] = hn::Mul(hn::Set(d, gm::kShC1), z);
  basis[3] = hn::Mul(hn::Set(d, -gm::kShC1), x);
  if (DEGREE > 1) {
    const FloatVec xx = hn::Mul(x, x), yy = hn::Mul(y, y), zz = hn::Mul(z, z);
    auto c = [&](float constant) { return hn::Set(d, constant); };
    basis[4] = hn::Mul(hn::Mul(c(gm::kShC2_0), x), y);
    basis[5] = hn::Mul(hn::Mul(c(gm::kShC2_1), y), z);
    basis[6] = hn::Mul(c(gm::kShC2_2), hn::Sub(hn::Sub(hn::Mul(c(2.0f), zz), xx), yy));
    basis[7] = hn::Mul(hn::Mul(c(gm::kShC2_3), x), z);
    basis[8] = hn::Mul(c(gm::kShC2_4), hn::Sub(xx, yy));
    if (DEGREE > 2) {
      const FloatVec four_zz_xx_yy = hn::Sub(hn::Sub(hn::Mul(c(4.0f), zz), xx), yy);
      basis[9] = hn::Mul(hn::Mul(c(gm::kShC3_0), y), hn::Sub(hn::Mul(c(3.0f), xx), yy));
      basis[10] = hn::Mul(hn::Mul(hn::Mul(c(gm::kShC3_1), x), y), z);
      basis[11] = hn::Mul(hn::Mul(c(gm::kShC3_2), y), four_zz_xx_yy);
      basis[12] = hn::Mul(hn::Mul(c(gm::kShC3_3), z),
                          hn::Sub(hn::Sub(hn::Mul(c(2.0f), zz), hn::Mul(c(3.0f), xx)), hn::Mul(c(3.0f), yy)));
      basis[13] = hn::Mul(hn::Mul(c(gm::kShC3_4), x), four_zz_xx_yy);
      basis[14] = hn::Mul(hn::Mul(c(gm::kShC3_5), z), hn::Sub(xx, yy));
      basis[15] = hn::Mul(hn::Mul(c(gm::kShC3_6), x), hn::Sub(xx, hn::Mul(c(3.0f), yy)));
    }
  }
  for (int k = 1; k < (DEGREE + 1) * (DEGREE + 1); ++k) hn::Store(basis[k], d, out.sh_basis[k]);
}

// gm::sh_to_rgb's sums for one Gaussian, its three channels in the lanes of one 4-lane vector:
// basis[0] dc, then + basis[k] rest[k - 1] for k = 1, 2, ... (the scalar order per channel). Each
// load takes 4 floats where the Gaussian has 3 from there on: the 4th (the next coefficient, or
// the next Gaussian's) lands in the unused lane; the scene's last Gaussian never comes here.
template <int DEGREE>
HWY_INLINE void sh_sums(const float* dc, const float* rest, const Lanes& v, std::size_t lane, float* rgb) {
  const hn::FixedTag<float, 4> d4;
  auto sum = hn::Mul(hn::Set(d4, gm::kShC0), hn::LoadU(d4, dc));
  for (int k = 1; k < (DEGREE + 1) * (DEGREE + 1); ++k)
    sum = hn::Add(sum, hn::Mul(hn::Set(d4, v.sh_basis[k][lane]), hn::LoadU(d4, rest + (k - 1) * 3)));
  const auto shifted = hn::Add(sum, hn::Set(d4, 0.5f));
  hn::StoreU(hn::IfThenElse(hn::Gt(shifted, hn::Zero(d4)), shifted, hn::Zero(d4)), d4, rgb);
}

// The visible lanes into Frame's arrays, as the scalar reference writes them.
template <int DEGREE>
void store_lanes(const SceneArrays& scene, Frame& frame, std::int64_t i,
                 std::size_t lanes, const Lanes& v) {
  const int rest_n = scene.rest_n;
  for (std::size_t l = 0; l < lanes; ++l) {
    const std::int64_t id = i + static_cast<std::int64_t>(l);
    frame.cull[id] = static_cast<std::uint8_t>(v.reason[l]);
    if (v.reason[l] != gm::kVisible) continue;
    gm::Footprint& f = frame.footprints[id];
    f.mean_x = v.mean_x[l];
    f.mean_y = v.mean_y[l];
    f.depth = v.depth[l];
    frame.depth_bits[id] = gm::depth_bits(f.depth);
    f.conic_a = v.conic_a[l];
    f.conic_b = v.conic_b[l];
    f.conic_c = v.conic_c[l];
    f.threshold = v.threshold[l];
    f.opacity = v.opacity[l];
    f.tile_x0 = v.tile_x0[l];
    f.tile_y0 = v.tile_y0[l];
    f.tile_x1 = v.tile_x1[l];
    f.tile_y1 = v.tile_y1[l];
    f.whiten[0] = v.w0[l];
    f.whiten[1] = v.w1[l];
    f.whiten[2] = v.w2[l];
    f.whiten[3] = v.w3[l];
    f.edge_slope_x = v.edge_slope_x[l];
    f.edge_slope_y = v.edge_slope_y[l];
    BlendGaussian& g = frame.blend_data[id];
    g.mean_x = f.mean_x;
    g.mean_y = f.mean_y;
    for (int k = 0; k < 4; ++k) g.whiten[k] = f.whiten[k];
    HWY_ALIGN float rgb[4];
    sh_sums<DEGREE>(scene.dc + id * 3, DEGREE > 0 ? scene.rest + id * rest_n : nullptr, v, l, rgb);
    for (int ch = 0; ch < 3; ++ch) g.rgb[ch] = rgb[ch];
    set_opacity_terms(frame, id, f.opacity, g);
    set_row_pruning(g);  // in double, per visible Gaussian
  }
}

template <int DEGREE, bool kOpacityRadius, bool kTightBox, bool kBaseline>
void project_vectors(const SceneArrays& scene, Frame& frame, std::int64_t begin,
                     std::int64_t end) {
  const std::int64_t lanes = static_cast<std::int64_t>(hn::Lanes(FloatTag()));
  Lanes v;
  for (std::int64_t i = begin; i < end; i += lanes) {
    if (project_vector<kOpacityRadius, kTightBox, kBaseline>(scene, frame, i, v))
      sh_basis_vector<DEGREE>(scene, frame, i, v);
    store_lanes<DEGREE>(scene, frame, i, static_cast<std::size_t>(lanes), v);
  }
}

template <int DEGREE>
void project_vectors_of_degree(const SceneArrays& scene, Frame& frame,
                               std::int64_t begin, std::int64_t end) {
  // The geometry is the frame's: one specialisation per combination, no branch per lane.
  const gm::GeometryParams& geo = frame.geometry;
  const int which = (geo.opacity_radius ? 4 : 0) | (geo.tight_bbox ? 2 : 0) | (geo.baseline ? 1 : 0);
  switch (which) {
    case 0: project_vectors<DEGREE, false, false, false>(scene, frame, begin, end); break;
    case 1: project_vectors<DEGREE, false, false, true>(scene, frame, begin, end); break;
    case 2: project_vectors<DEGREE, false, true, false>(scene, frame, begin, end); break;
    case 3: project_vectors<DEGREE, false, true, true>(scene, frame, begin, end); break;
    case 4: project_vectors<DEGREE, true, false, false>(scene, frame, begin, end); break;
    case 5: project_vectors<DEGREE, true, false, true>(scene, frame, begin, end); break;
    case 6: project_vectors<DEGREE, true, true, false>(scene, frame, begin, end); break;
    default: project_vectors<DEGREE, true, true, true>(scene, frame, begin, end); break;
  }
}

void ProjectBlock(const SceneArrays& scene, int degree, Frame& frame,
                  std::int64_t begin, std::int64_t end) {
  const std::int64_t lanes = static_cast<std::int64_t>(hn::Lanes(FloatTag()));
  // The scene's last Gaussian goes to the scalar code: sh_sums reads a float past its coefficients.
  const std::int64_t vector_limit = std::min(end, scene.count - 1);
  const std::int64_t vector_end = begin + std::max<std::int64_t>(0, vector_limit - begin) / lanes * lanes;
  switch (degree) {
    case 0: project_vectors_of_degree<0>(scene, frame, begin, vector_end); break;
    case 1: project_vectors_of_degree<1>(scene, frame, begin, vector_end); break;
    case 2: project_vectors_of_degree<2>(scene, frame, begin, vector_end); break;
    default: project_vectors_of_degree<3>(scene, frame, begin, vector_end); break;
  }
  project_block_scalar(scene, degree, frame, vector_end, end);  // the tail: fewer than a vector
}
#endif  // HWY_TARGET == HWY_SCALAR

}  // namespace HWY_NAMESPACE
}  // namespace cpu
}  // namespace flashgs
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace flashgs {
namespace cpu {

HWY_EXPORT(ProjectBlock);

void project_block_simd(const SceneArrays& scene, int degree, Frame& frame,
                        std::int64_t begin, std::int64_t end) {
  HWY_DYNAMIC_DISPATCH(ProjectBlock)(scene, degree, frame, begin, end);
}

}  // namespace cpu
}  // namespace flashgs
#endif  // HWY_ONCE

#else  // no Highway: the scalar reference

namespace flashgs {
namespace cpu {

void project_block_simd(const SceneArrays& scene, int degree, Frame& frame,
                        std::int64_t begin, std::int64_t end) {
  project_block_scalar(scene, degree, frame, begin, end);
}

}  // namespace cpu
}  // namespace flashgs
#endif
