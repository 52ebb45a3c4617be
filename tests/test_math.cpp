// Unit tests of the shared per-Gaussian math: log, projection, exact ellipse-tile test, SH.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "flashgs/frame_params.h"
#include "flashgs/gaussian_math.h"

namespace flashgs {
namespace {

TEST(PortableLog, MatchesStdLogToAFewUlp) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> exponent(-40.0f, 40.0f);
  double worst = 0;
  for (int i = 0; i < 200000; ++i) {
    const float x = std::pow(2.0f, exponent(rng));
    const double expected = std::log(static_cast<double>(x));
    const double err = std::abs(gm::portable_log(x) - expected);
    worst = std::max(worst, err / std::max(1.0, std::abs(expected)));
  }
  EXPECT_LT(worst, 4e-7) << "portable_log is the extent of every flash Gaussian";
  EXPECT_TRUE(std::isinf(gm::portable_log(0.0f)));
  EXPECT_NEAR(gm::portable_log(1e-40f), std::log(1e-40), 1e-4);  // subnormal input
}

Camera test_camera(int width, int height) {
  const float c2w[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  const float centre[3] = {0, 0, 0};
  return Camera::from_pose(width, height, 0.8f * width, 0.8f * width, c2w, centre);
}

// A random Gaussian in front of the camera: position, scales over 4 decades, any rotation.
struct RandomGaussian {
  float position[3], scale[3], quat[4], opacity;
};

RandomGaussian random_gaussian(std::mt19937& rng) {
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  RandomGaussian g;
  const float z = 1.0f + 9.0f * uni(rng);
  g.position[0] = (uni(rng) - 0.5f) * z * 1.6f;
  g.position[1] = (uni(rng) - 0.5f) * z;
  g.position[2] = z;
  for (float& s : g.scale) s = std::pow(10.0f, -3.0f + 2.5f * uni(rng));
  float n = 0;
  for (float& q : g.quat) { q = normal(rng); n += q * q; }
  for (float& q : g.quat) q /= std::sqrt(n);
  g.opacity = 0.005f + 0.995f * uni(rng);
  return g;
}

// The guarantee the flash path rests on: a tile is never dropped when a pixel centre in it
// has alpha >= tau (q <= threshold). Checked against every pixel centre of every tile in a
// window around the box; false positives (tiles kept that no pixel needs) are counted.
TEST(ExactTileTest, NeverDropsATileWherePixelsReachTau) {
  const Camera camera = test_camera(256, 192);
  const gm::CameraParams cam = make_camera_params(camera);
  std::mt19937 rng(42);
  long kept = 0, needed = 0, false_positive = 0, box_misses = 0;
  for (int variant = 0; variant < 4; ++variant) {
    RenderOptions options;
    options.opacity_aware_radius = variant & 1;
    options.tight_bbox = (variant & 2) != 0;
    const gm::GeometryParams geo = make_geometry_params(options);
    for (int n = 0; n < 1500; ++n) {
      const RandomGaussian g = random_gaussian(rng);
      gm::Footprint f;
      if (gm::project(cam, geo, g.position, g.scale, g.quat, g.opacity, f) != gm::kVisible) continue;
      for (int ty = 0; ty < cam.tiles_y; ++ty)
        for (int tx = 0; tx < cam.tiles_x; ++tx) {
          bool pixel_needs_tile = false;
          for (int y = ty * 16; y < std::min(ty * 16 + 16, cam.height) && !pixel_needs_tile; ++y)
            for (int x = tx * 16; x < std::min(tx * 16 + 16, cam.width); ++x) {
              const float dx = x - f.mean_x, dy = y - f.mean_y;
              if (f.conic_a * dx * dx + 2 * f.conic_b * dx * dy + f.conic_c * dy * dy <= f.threshold) {
                pixel_needs_tile = true;
                break;
              }
            }
          const bool in_box = tx >= f.tile_x0 && tx < f.tile_x1 && ty >= f.tile_y0 && ty < f.tile_y1;
          const bool test = in_box && gm::footprint_touches_tile(f, tx, ty, cam.width, cam.height);
          if (pixel_needs_tile) {
            ++needed;
            EXPECT_TRUE(in_box) << "box misses a needed tile";
            EXPECT_TRUE(test) << "exact test drops a needed tile (" << tx << "," << ty << ")";
            box_misses += in_box ? 0 : 1;
          }
          if (test) ++kept;
          if (test && !pixel_needs_tile) ++false_positive;
        }
    }
  }
  ASSERT_GT(needed, 1000);
  EXPECT_EQ(box_misses, 0);
  std::printf("exact tile test: %ld tiles kept, %ld needed, %ld false positives (%.2f%%)\n", kept, needed,
              false_positive, 100.0 * false_positive / std::max(1L, kept));
  // A tile is kept needlessly only when the ellipse crosses the rectangle of its pixel
  // centres between two of them (measured 0.16%); a test that kept whole boxes would keep
  // ~30% more tiles than needed.
  EXPECT_LT(false_positive, kept / 100) << "the exact test keeps tiles no pixel needs";
}

// whitened_ellipse_meets_rect for the conic [a b; b c] with principal axes u (unit) and
// (-u_y, u_x) of standard deviations s_major, s_minor.
bool meets(float ux, float uy, float s_major, float s_minor, float t, float dx0, float dx1, float dy0, float dy1) {
  const float w[4] = {ux / s_major, uy / s_major, -uy / s_minor, ux / s_minor};
  const float a = w[0] * w[0] + w[2] * w[2], b = w[0] * w[1] + w[2] * w[3], c = w[1] * w[1] + w[3] * w[3];
  return gm::whitened_ellipse_meets_rect(w, -b / c, -b / a, t, dx0, dx1, dy0, dy1);
}

TEST(ExactTileTest, EllipseRectCases) {
  // Unit circle q = dx^2 + dy^2 <= 1.
  EXPECT_TRUE(meets(1, 0, 1, 1, 1, -1, 1, -1, 1));          // centre inside
  EXPECT_TRUE(meets(1, 0, 1, 1, 1, 0.5f, 2, -1, 1));        // edge crosses
  EXPECT_FALSE(meets(1, 0, 1, 1, 1, 1.5f, 2, -1, 1));       // right of the circle
  EXPECT_FALSE(meets(1, 0, 1, 1, 1, 0.75f, 2, 0.75f, 2));   // corner outside (0.75^2*2 > 1)
  EXPECT_TRUE(meets(1, 0, 1, 1, 1, 0.7f, 2, 0.7f, 2));      // corner inside (0.98 <= 1)
  EXPECT_TRUE(meets(1, 0, 1, 1, 1, -1, 1, 0.5f, 2));        // spans the centre's column, bottom edge crosses
  EXPECT_FALSE(meets(1, 0, 1, 1, 1, -1, 1, 1.5f, 2));       // spans the column, below the circle
  EXPECT_FALSE(meets(1, 0, 1, 1, 1, -3, -1.01f, -0.2f, 0.2f));  // left of the circle, spanning its row
  // A thin diagonal needle along x = y (sigma 10 along it, 0.1 across): reaches (3, 3) but
  // not (3, -3).
  const float h = std::sqrt(0.5f);
  EXPECT_TRUE(meets(h, h, 10, 0.1f, 1, 2.5f, 3.5f, 2.5f, 3.5f));
  EXPECT_FALSE(meets(h, h, 10, 0.1f, 1, 2.5f, 3.5f, -3.5f, -2.5f));
  // The same needle and a wide rectangle across its path away from its centre: only the edge
  // minimiser (slope times the edge's offset, clamped) finds where the needle crosses it.
  EXPECT_TRUE(meets(h, h, 10, 0.1f, 1, -20, 20, 6.5f, 7.5f));
  EXPECT_FALSE(meets(h, h, 10, 0.1f, 1, -20, 5, 6.5f, 7.5f));
  EXPECT_FALSE(meets(h, h, 10, 0.1f, 1, -20, 20, 9.5f, 10.5f));  // beyond its reach: q = 2 at (10, 10)
}

// q's minimum over a rectangle, as the CUDA blend's stop bound uses it (the least share of T a
// Gaussian can leave a pixel of an 8x8 region): no point of the rectangle may have a smaller q,
// beyond float rounding. Random footprints, regions at random offsets from their centres,
// each rectangle sampled on a 33 x 33 grid (pixel centres and points between them).
TEST(ExactTileTest, RectMinimumOfQIsALowerBoundOverTheRect) {
  const Camera camera = test_camera(256, 192);
  const gm::CameraParams cam = make_camera_params(camera);
  const gm::GeometryParams geo = make_geometry_params(RenderOptions{});
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> uni(-1.0f, 1.0f);
  int rects = 0, centre_outside = 0;
  double worst_excess = 0;  // how far below q_min a sample went, relative to max(1, q_min)
  for (int n = 0; n < 3000; ++n) {
    const RandomGaussian g = random_gaussian(rng);
    gm::Footprint f;
    if (gm::project(cam, geo, g.position, g.scale, g.quat, g.opacity, f) != gm::kVisible) continue;
    // Regions within a few sigma: offsets up to ~4x the threshold ellipse's reach plus the region.
    const float reach = 4.0f * std::sqrt(f.threshold / std::min(f.conic_a, f.conic_c)) + 8.0f;
    for (int r = 0; r < 4; ++r) {
      const float x0 = f.mean_x + std::min(reach, 200.0f) * uni(rng), y0 = f.mean_y + std::min(reach, 200.0f) * uni(rng);
      const float dx0 = x0 - f.mean_x, dx1 = dx0 + 7.0f, dy0 = y0 - f.mean_y, dy1 = dy0 + 7.0f;
      const float q_min = gm::whitened_q_min_on_rect(f.whiten, f.edge_slope_x, f.edge_slope_y, dx0, dx1, dy0, dy1);
      ++rects;
      centre_outside += (dx0 > 0 || dx1 < 0 || dy0 > 0 || dy1 < 0) ? 1 : 0;
      for (int i = 0; i <= 32; ++i)
        for (int j = 0; j <= 32; ++j) {
          const float q = gm::whitened_q(f.whiten, dx0 + 7.0f * i / 32, dy0 + 7.0f * j / 32);
          worst_excess = std::max(worst_excess, (q_min - q) / std::max(1.0, static_cast<double>(q_min)));
        }
    }
  }
  ASSERT_GT(centre_outside, 2000) << "too few rectangles away from the centre to test the edge minimisers";
  std::printf("q minimum over %d rectangles (%d without the centre): worst sample below it by %.3g (relative)\n",
              rects, centre_outside, worst_excess);
  // The blend's margin is 1e-3 in log2 alpha, for q of a few units: this is 100 times tighter.
  EXPECT_LT(worst_excess, 1e-5);
}

// 3DGS's radius is ceil(3 sqrt(mid + sqrt(max(0.1, mid^2 - det)))): the smallest footprint
// (covariance 0.3 I from the dilation alone) gets radius ceil(3 sqrt(0.3 + sqrt(0.1))) = 3,
// not ceil(3 sqrt(0.3)) = 2. With its centre at x = 14.25, getRect's last tile is
// trunc((14.25 + r + 15) / 16) - 1: tile 1 for r = 3, tile 0 for r = 2.
TEST(BaselineRadius, FollowsThe3dgsEigenvalueFloor) {
  const gm::CameraParams cam = make_camera_params(test_camera(64, 64));
  const gm::GeometryParams geo = make_geometry_params(RenderOptions::baseline());
  const float z = 5.0f, quat[4] = {1, 0, 0, 0};
  const float position[3] = {(14.25f - cam.cx) * z / cam.fx, (14.25f - cam.cy) * z / cam.fy, z};
  const float dot[3] = {1e-5f, 1e-5f, 1e-5f};
  gm::Footprint f;
  ASSERT_EQ(gm::project(cam, geo, position, dot, quat, 0.9f, f), gm::kVisible);
  ASSERT_NEAR(f.mean_x, 14.25f, 1e-3f);
  EXPECT_EQ(f.tile_x0, 0);
  EXPECT_EQ(f.tile_x1, 2) << "radius 3 reaches tile 1";
  EXPECT_EQ(f.tile_y1, 2);
}

// A needle with scale ratio 1e6: the 2D determinant computed as a*c - b*b in float is noise,
// the Cauchy-Binet form must agree with a double computation.
TEST(Projection, StiffCovarianceKeepsAPositiveAccurateConic) {
  const Camera camera = test_camera(512, 512);
  const gm::CameraParams cam = make_camera_params(camera);
  const gm::GeometryParams geo = make_geometry_params(RenderOptions::baseline());
  const float position[3] = {0.1f, 0.05f, 4.0f};
  const float scale[3] = {1.0f, 1e-6f, 1e-6f};
  const float s = std::sqrt(0.5f);
  const float quat[4] = {s, 0, 0, s};  // needle rotated into the image plane
  gm::Footprint f;
  ASSERT_EQ(gm::project(cam, geo, position, scale, quat, 0.9f, f), gm::kVisible);
  EXPECT_GT(f.conic_a, 0);
  EXPECT_GT(f.conic_c, 0);
  EXPECT_GT(f.conic_a * f.conic_c - f.conic_b * f.conic_b, 0);
  // In double: the covariance is ((J R S)(J R S)^T) + 0.3 I; the needle lies along y on
  // screen, so sigma_yy ~ (fy * 1 / 4)^2 and sigma_xx ~ 0.3.
  const double fy = camera.fy, sigma_yy = std::pow(fy / 4.0, 2) + 0.3;
  EXPECT_NEAR(1.0 / f.conic_a, 0.3, 0.3 * 1e-3);  // conic_a ~ 1 / sigma_xx when b ~ 0
  EXPECT_NEAR(f.conic_c, 1.0 / sigma_yy, 1e-3 / sigma_yy);
}

TEST(Projection, CullsNearAndDegenerate) {
  const gm::CameraParams cam = make_camera_params(test_camera(64, 64));
  const gm::GeometryParams geo = make_geometry_params(RenderOptions{});
  const float scale[3] = {0.1f, 0.1f, 0.1f}, quat[4] = {1, 0, 0, 0};
  gm::Footprint f;
  const float behind[3] = {0, 0, -1}, at_near[3] = {0, 0, 0.2f}, nan_pos[3] = {NAN, 0, 1};
  EXPECT_EQ(gm::project(cam, geo, behind, scale, quat, 0.9f, f), gm::kCulledNear);
  EXPECT_EQ(gm::project(cam, geo, at_near, scale, quat, 0.9f, f), gm::kCulledNear);
  EXPECT_EQ(gm::project(cam, geo, nan_pos, scale, quat, 0.9f, f), gm::kCulledDegenerate);
  const float front[3] = {0, 0, 2};
  EXPECT_EQ(gm::project(cam, geo, front, scale, quat, 0.5f / 255.0f, f), gm::kCulledLowOpacity);
  const float huge[3] = {1e30f, 1e30f, 1e30f};  // radius overflows: culled, never UB
  EXPECT_NE(gm::project(cam, geo, front, huge, quat, 0.9f, f), gm::kVisible);
}

TEST(Projection, OpacityAwareExtentMatchesTheAlphaThreshold) {
  const gm::CameraParams cam = make_camera_params(test_camera(128, 128));
  RenderOptions options;
  const gm::GeometryParams geo = make_geometry_params(options);
  const float position[3] = {0, 0, 5}, scale[3] = {0.05f, 0.05f, 0.05f}, quat[4] = {1, 0, 0, 0};
  gm::Footprint f;
  ASSERT_EQ(gm::project(cam, geo, position, scale, quat, 0.8f, f), gm::kVisible);
  // At q = threshold alpha equals tau.
  EXPECT_NEAR(0.8 * std::exp(-0.5 * f.threshold), options.tau, 1e-6);
}

TEST(SphericalHarmonics, DegreeZeroIsTheDcTerm) {
  const float cam[3] = {0, 0, 0}, pos[3] = {1, 2, 3}, dc[3] = {1.0f, -1.0f, 0.0f};
  float rgb[3];
  gm::sh_to_rgb<0>(cam, pos, dc, nullptr, rgb);
  EXPECT_NEAR(rgb[0], 0.5f + gm::kShC0, 1e-6);
  EXPECT_NEAR(rgb[1], 0.5f - gm::kShC0, 1e-6);
  EXPECT_NEAR(rgb[2], 0.5f, 1e-6);
}

TEST(SphericalHarmonics, BandOneFollowsTheViewDirection) {
  // Coefficient 3 multiplies -C1 * x: seen along +x the colour drops, along -x it rises.
  const float cam[3] = {0, 0, 0}, dc[3] = {0, 0, 0};
  float rest[9] = {0, 0, 0, 0, 0, 0, 1, 1, 1};
  const float along_x[3] = {1, 0, 0}, against_x[3] = {-1, 0, 0};
  float a[3], b[3];
  gm::sh_to_rgb<1>(cam, along_x, dc, rest, a);
  gm::sh_to_rgb<1>(cam, against_x, dc, rest, b);
  EXPECT_NEAR(a[0], std::max(0.0f, 0.5f - gm::kShC1), 1e-6);
  EXPECT_NEAR(b[0], 0.5f + gm::kShC1, 1e-6);
}

// The compiler's own half type (GCC 12+, Clang 15+ on x86-64), the independent reference for
// the rounding tests below; a compiler without one skips them.
#ifdef __FLT16_MAX__
#define FLASHGS_HAVE_FLOAT16 1
#else
#define FLASHGS_HAVE_FLOAT16 0
#endif

#if FLASHGS_HAVE_FLOAT16
std::uint32_t float_bits(float v) {
  std::uint32_t bits;
  std::memcpy(&bits, &v, 4);
  return bits;
}

float float_from_bits(std::uint32_t bits) {
  float v;
  std::memcpy(&v, &bits, 4);
  return v;
}

// GCC's conversion to _Float16 (round to nearest even, in hardware or libgcc), as bits.
std::uint16_t gcc_half_bits(float v) {
  const _Float16 h = static_cast<_Float16>(v);
  std::uint16_t bits;
  std::memcpy(&bits, &h, 2);
  return bits;
}

// The values where a rounding goes wrong first: every half and the midpoints between
// neighbours (ties, to even) with a float ulp either side, subnormals and the smallest values
// included, and random floats of every exponent up to the half range, both signs.
std::vector<float> half_rounding_cases() {
  std::vector<float> cases;
  cases.insert(cases.end(), {65504.0f, -65504.0f});
  for (std::uint32_t h = 0; h < 0x7bffu; ++h) {  // up to the largest half, whose next is Inf
    const float v = gm::half_bits_to_float(static_cast<std::uint16_t>(h));
    const float next = gm::half_bits_to_float(static_cast<std::uint16_t>(h + 1));
    const float tie = v + 0.5f * (next - v);  // exact: a float has 13 more mantissa bits
    for (float c : {v, tie, std::nextafter(tie, 0.0f), std::nextafter(tie, 1e9f)}) {
      cases.push_back(c);
      cases.push_back(-c);
    }
  }
  for (float tiny : {1e-45f, 1e-40f, 2.9802322e-8f, 2.9802326e-8f, 3e-8f, 5.9604645e-8f, 6.1035156e-5f})
    cases.insert(cases.end(), {tiny, -tiny});
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::uint32_t> bits(0, 0x477fefffu);  // below 65520, where halves end
  for (int i = 0; i < 1000000; ++i) cases.push_back(float_from_bits(bits(rng) | (i % 2 ? 0x80000000u : 0u)));
  return cases;
}
#endif

TEST(HalfRounding, MatchesGccFloat16BitForBit) {
#if !FLASHGS_HAVE_FLOAT16
  GTEST_SKIP() << "this compiler has no _Float16 to compare with";
#else
  int mismatches = 0;
  for (float v : half_rounding_cases()) {
    const std::uint16_t ours = gm::float_to_half_bits(v), gcc = gcc_half_bits(v);
    if (ours != gcc && ++mismatches <= 10)
      ADD_FAILURE() << std::hexfloat << v << ": 0x" << std::hex << ours << ", GCC 0x" << gcc;
  }
  EXPECT_EQ(mismatches, 0);
#endif
}

TEST(HalfRounding, EveryHalfConvertsBackExactly) {
#if !FLASHGS_HAVE_FLOAT16
  GTEST_SKIP() << "this compiler has no _Float16 to compare with";
#else
  for (std::uint32_t h = 0; h < 0x10000u; ++h) {
    if (((h >> 10) & 0x1fu) == 0x1fu) continue;  // Inf and NaN: never encoded
    const std::uint16_t half = static_cast<std::uint16_t>(h);
    _Float16 gcc;
    std::memcpy(&gcc, &half, 2);
    ASSERT_EQ(float_bits(gm::half_bits_to_float(half)), float_bits(static_cast<float>(gcc))) << std::hex << h;
    ASSERT_EQ(gm::float_to_half_bits(gm::half_bits_to_float(half)), half) << std::hex << h;
  }
#endif
}

// Beyond the half range the value clamps to the largest half instead of becoming infinite.
TEST(HalfRounding, ValuesBeyondTheRangeClampTo65504) {
  for (float v : {65504.0f, 65519.996f, 65520.0f, 1e6f, 3.4e38f}) {
    EXPECT_EQ(gm::round_to_half(v), 65504.0f) << v;
    EXPECT_EQ(gm::round_to_half(-v), -65504.0f) << v;
  }
  EXPECT_EQ(gm::round_to_half(65503.0f), 65504.0f);
  EXPECT_EQ(gm::round_to_half(65487.0f), 65472.0f);  // below the midpoint 65488 of the last two halves
}

}  // namespace
}  // namespace flashgs
