// Stress scenes (see stress_scenes.h): each case is built procedurally and deterministically,
// together with the error bound against the fp64 reference that it must meet and the reason.
#include "flashgs/stress_scenes.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <sstream>

#include <unistd.h>

#include "flashgs/error.h"
#include "flashgs/file_write.h"
#include "flashgs/gaussian_math.h"
#include "flashgs/io.h"
#include "flashgs/options.h"

namespace flashgs {
namespace {

// A small portable generator (xorshift64*), so that a case is the same on every platform
// (std:: distributions are implementation-defined).
struct Rng {
  std::uint64_t state;
  explicit Rng(std::uint64_t seed) : state(seed * 0x9E3779B97F4A7C15ull + 1) {}
  std::uint64_t next() {
    state ^= state >> 12;
    state ^= state << 25;
    state ^= state >> 27;
    return state * 0x2545F4914F6CDD1Dull;
  }
  float uniform() { return static_cast<float>(next() >> 40) / 16777216.0f; }  // [0, 1)
  float range(float lo, float hi) { return lo + (hi - lo) * uniform(); }
};

void random_quaternion(Rng& rng, float q[4]) {
  for (;;) {
    double n = 0;
    for (int k = 0; k < 4; ++k) {
      q[k] = rng.range(-1.0f, 1.0f);
      n += static_cast<double>(q[k]) * q[k];
    }
    if (n > 0.01 && n <= 1.0) {
      const double inv = 1.0 / std::sqrt(n);
      for (int k = 0; k < 4; ++k) q[k] = static_cast<float>(q[k] * inv);
      return;
    }
  }
}

// Quaternion rotating +x onto the unit vector d (computed in double, then rounded).
void quaternion_x_to(double dx, double dy, double dz, float q[4]) {
  const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
  dx /= len;
  dy /= len;
  dz /= len;
  if (dx < -0.999999) {
    q[0] = 0; q[1] = 0; q[2] = 1; q[3] = 0;
    return;
  }
  double w = 1.0 + dx, x = 0.0, y = -dz, z = dy;  // axis = x cross d
  const double n = std::sqrt(w * w + x * x + y * y + z * z);
  q[0] = static_cast<float>(w / n);
  q[1] = static_cast<float>(x / n);
  q[2] = static_cast<float>(y / n);
  q[3] = static_cast<float>(z / n);
}

void add(Scene& s, float x, float y, float z, float sx, float sy, float sz, const float q[4], float opacity,
         float r, float g, float b) {
  const float p[3] = {x, y, z}, sc[3] = {sx, sy, sz}, rgb[3] = {r, g, b};
  for (int k = 0; k < 3; ++k) {
    s.positions.push_back(p[k]);
    s.scales.push_back(sc[k]);
    s.sh_dc.push_back((rgb[k] - 0.5f) / gm::kShC0);
  }
  for (int k = 0; k < 4; ++k) s.rotations.push_back(q[k]);
  s.opacities.push_back(opacity);
  for (int k = 0; k < s.sh_rest_per_gaussian(); ++k) s.sh_rest.push_back(0.0f);
}

const float kIdentity[4] = {1, 0, 0, 0};

void hue(float t, float rgb[3]) {
  rgb[0] = 0.5f + 0.45f * std::cos(6.2831853f * t);
  rgb[1] = 0.5f + 0.45f * std::cos(6.2831853f * (t - 0.333f));
  rgb[2] = 0.5f + 0.45f * std::cos(6.2831853f * (t - 0.667f));
}

// A camera at `eye` looking at `target` (OpenCV axes: x right, y down, z forward), `up`
// pointing up in the image. Horizontal field of view in degrees.
Camera look_at(int width, int height, double fov_degrees, const double eye[3], const double target[3],
               const double up[3]) {
  double z[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
  double n = std::sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2]);
  for (double& v : z) v /= n;
  // x = z cross up points right when up is up (y down in the image)
  double x[3] = {z[1] * up[2] - z[2] * up[1], z[2] * up[0] - z[0] * up[2], z[0] * up[1] - z[1] * up[0]};
  n = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
  for (double& v : x) v /= n;
  const double y[3] = {z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]};
  float c2w[9], centre[3];
  for (int r = 0; r < 3; ++r) {
    c2w[r * 3 + 0] = static_cast<float>(x[r]);
    c2w[r * 3 + 1] = static_cast<float>(y[r]);
    c2w[r * 3 + 2] = static_cast<float>(z[r]);
    centre[r] = static_cast<float>(eye[r]);
  }
  const float f = static_cast<float>(0.5 * width / std::tan(0.5 * fov_degrees * M_PI / 180.0));
  return Camera::from_pose(width, height, f, f, c2w, centre);
}

// The camera at the origin looking down +z (identity rotation): view-space z equals world z,
// so depths in these scenes are exact.
Camera axis_camera(int width, int height, double fov_degrees) {
  const float c2w[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, centre[3] = {0, 0, 0};
  const float f = static_cast<float>(0.5 * width / std::tan(0.5 * fov_degrees * M_PI / 180.0));
  return Camera::from_pose(width, height, f, f, c2w, centre);
}

// ---------------------------------------------------------------------------------------
// Error bounds. Every backend renders in float; the reference in double with the same rules.
// Three things separate them:
//  (1) rounding of the conic, the exponent and the compositing: a few float ulps of each
//      alpha, amplified by the quadratic form's size; 1e-4 of full scale covers it for
//      well-conditioned footprints (measured: ~1e-6).
//  (2) a threshold decided on the other side (alpha vs 1/255, T vs 1e-4): one flip changes a
//      pixel by at most alpha * T * |rgb - what is behind| <= 1/255 for the alpha test.
//  (3) the baseline's box (3DGS, reproduced on purpose): radius r = ceil(3 sqrt(lambda)),
//      lambda = mid + sqrt(max(0.1, mid^2 - det)) >= the largest variance, and getRect's
//      trunc((x + r + 15) / 16), which leaves out the tile in whose first pixel x + r falls,
//      so a pixel more than r - 1 from the centre (along x or y) can lose the Gaussian. There
//      q >= (r - 1)^2 / lambda: the floor makes lambda >= 0.3 + sqrt(0.1), so r >= 3; for
//      lambda <= 1, r = 3 and q >= 4; above, q >= (3 - 1 / sqrt(lambda))^2 > 4. One cut is
//      therefore at most 0.99 e^-2 = 0.134 (a footprint elongated along x with variance 1
//      there; an isotropic one, whose variance is lambda - sqrt(0.1), at most 0.053). Beyond
//      the box, q >= 9: alpha <= 0.011. The flash extent sqrt(2 ln(o / tau)) and its
//      pixel-exact box have no such cut.
constexpr double kRounding = 1e-4;
constexpr double kOneFlip = 1.0 / 255.0;
constexpr double kBoxCut = 0.99 * 0.1353352832366127;  // 0.99 e^-2

// The baseline's bound adds one box cut to the flash bound.
constexpr const char* kBaselineWhy = "; baseline: + one cut by 3DGS's box (0.99 e^-2 = 0.134, see kBoxCut)";

void set_bounds(StressCase& c, double flash, const std::string& reason) {
  c.bound_flash = flash;
  c.bound_baseline = flash + kBoxCut;
  c.bound_reason = reason + kBaselineWhy;
}

// Needles and pancakes with scale ratio `ratio` (largest / smallest), at random rotations and
// seen edge-on / face-on / end-on / side-on.
StressCase stiff_case(const std::string& name, double ratio, std::uint64_t seed) {
  StressCase c;
  c.name = name;
  char text[256];
  std::snprintf(text, sizeof text,
                "needles and pancakes with scale ratio %.0e at random rotations, end-on, side-on, face-on and "
                "edge-on",
                ratio);
  c.description = text;
  Scene& s = c.scene;
  Rng rng(seed);
  const float large = 0.6f, small = static_cast<float>(0.6 / ratio);
  int i = 0;
  for (int gy = 0; gy < 5; ++gy)
    for (int gx = 0; gx < 6; ++gx, ++i) {
      const float x = (gx - 2.5f) * 1.3f + rng.range(-0.1f, 0.1f), y = (gy - 2.0f) * 1.3f + rng.range(-0.1f, 0.1f);
      const float z = 5.0f + rng.range(-1.0f, 1.0f);
      float q[4], rgb[3];
      hue(static_cast<float>(i) / 30.0f, rgb);
      const float opacity = rng.range(0.3f, 1.0f);
      switch (gx) {
        case 0: random_quaternion(rng, q); add(s, x, y, z, large, small, small, q, opacity, rgb[0], rgb[1], rgb[2]); break;
        case 1: random_quaternion(rng, q); add(s, x, y, z, large, large, small, q, opacity, rgb[0], rgb[1], rgb[2]); break;
        case 2: add(s, x, y, z, small, small, large, kIdentity, opacity, rgb[0], rgb[1], rgb[2]); break;  // end-on
        case 3:  // side-on needle in the image plane at a steep angle
          quaternion_x_to(1.0, 0.8 + 0.1 * gy, 0.0, q);
          add(s, x, y, z, large, small, small, q, opacity, rgb[0], rgb[1], rgb[2]);
          break;
        case 4: add(s, x, y, z, large, large, small, kIdentity, opacity, rgb[0], rgb[1], rgb[2]); break;  // face-on
        default:  // edge-on pancake: its normal (x) lies in the image plane
          add(s, x, y, z, small, large, large, kIdentity, opacity, rgb[0], rgb[1], rgb[2]);
          break;
      }
    }
  c.cameras.push_back(axis_camera(256, 256, 100.0));
  // A second, oblique view so that no axis is aligned with the camera.
  const double eye[3] = {3.0, -2.0, -1.0}, target[3] = {0.0, 0.0, 5.0}, up[3] = {0.2, -1.0, 0.1};
  c.cameras.push_back(look_at(256, 192, 90.0, eye, target, up));
  set_bounds(c, kRounding + kOneFlip, "rounding (1e-4) + one alpha-threshold flip (1/255)");
  return c;
}

StressCase stiff_extreme_case() {
  StressCase c;
  c.name = "stiff_extreme";
  c.description = "smallest scale 1e-9 and largest 1e4 in one Gaussian: needles across the screen, a face-on "
                  "background plane, an edge-on plane, end-on needles, 1e-9 dots";
  Scene& s = c.scene;
  float q[4];
  quaternion_x_to(1.0, 0.9, 0.0, q);
  add(s, 0.0f, 0.0f, 20.0f, 1e4f, 1e-9f, 1e-9f, q, 0.9f, 1.0f, 0.2f, 0.2f);  // needle across the screen
  Rng rng(17);
  random_quaternion(rng, q);
  add(s, 1.0f, -1.0f, 30.0f, 1e4f, 1e-9f, 1e-9f, q, 0.8f, 0.2f, 1.0f, 0.2f);  // needle, random direction
  add(s, 0.0f, 0.0f, 100.0f, 1e4f, 1e4f, 1e-9f, kIdentity, 0.5f, 0.3f, 0.3f, 0.9f);  // face-on plane
  add(s, 2.0f, 0.5f, 50.0f, 1e-9f, 1e4f, 1e4f, kIdentity, 0.9f, 0.9f, 0.9f, 0.1f);   // edge-on plane
  add(s, -3.0f, 2.0f, 40.0f, 1e-9f, 1e-9f, 1e4f, kIdentity, 0.9f, 0.1f, 0.9f, 0.9f); // end-on needle
  for (int k = 0; k < 8; ++k)  // 1e-9 dots: only the 0.3 px^2 dilation is left
    add(s, -4.0f + k, 3.0f, 10.0f, 1e-9f, 1e-9f, 1e-9f, kIdentity, 0.9f, 1.0f, 1.0f, 1.0f);
  c.cameras.push_back(axis_camera(256, 256, 90.0));
  const double eye[3] = {5.0, 3.0, -2.0}, target[3] = {0.0, 0.0, 30.0}, up[3] = {0.0, -1.0, 0.0};
  c.cameras.push_back(look_at(256, 256, 70.0, eye, target, up));
  set_bounds(c, kRounding + kOneFlip, "as the stiff cases: rounding + one threshold flip");
  return c;
}

StressCase near_plane_case() {
  StressCase c;
  c.name = "near_plane";
  c.description = "Gaussians straddling the near plane z = 0.2, exactly on it, just in front, at z = 0, behind "
                  "the camera (near and far)";
  Scene& s = c.scene;
  add(s, 0.0f, 0.0f, 0.1f, 0.5f, 0.5f, 0.5f, kIdentity, 0.9f, 1, 0, 0);    // straddles: culled (3DGS rule)
  add(s, 0.05f, 0.0f, 0.2f, 0.02f, 0.02f, 0.02f, kIdentity, 0.9f, 1, 1, 0); // on the plane: culled
  add(s, -0.02f, 0.01f, std::nextafter(0.2f, 1.0f), 0.003f, 0.001f, 0.002f, kIdentity, 0.7f, 0, 1, 0);  // just in
  add(s, 0.05f, -0.05f, 0.25f, 0.01f, 0.02f, 0.005f, kIdentity, 0.8f, 0, 1, 1);
  add(s, 0.3f, 0.0f, 0.0f, 0.5f, 0.5f, 0.5f, kIdentity, 0.9f, 1, 0, 1);     // z = 0
  add(s, 0.0f, 0.0f, -0.0f, 0.5f, 0.5f, 0.5f, kIdentity, 0.9f, 1, 0, 1);    // z = -0
  add(s, 0.0f, 0.0f, -1.0f, 2.0f, 2.0f, 2.0f, kIdentity, 0.9f, 0, 0, 1);    // behind
  add(s, 0.0f, 0.0f, -1e6f, 1e5f, 1e5f, 1e5f, kIdentity, 0.9f, 1, 1, 1);    // far behind, huge
  add(s, 0.0f, 0.0f, -1e-30f, 1.0f, 1.0f, 1.0f, kIdentity, 0.9f, 1, 1, 1);  // a hair behind
  Rng rng(3);
  for (int k = 0; k < 12; ++k) {
    float q[4];
    random_quaternion(rng, q);
    add(s, rng.range(-2, 2), rng.range(-2, 2), rng.range(2, 5), 0.3f, 0.1f, 0.05f, q, 0.8f, rng.uniform(),
        rng.uniform(), rng.uniform());
  }
  c.cameras.push_back(axis_camera(128, 128, 90.0));
  set_bounds(c, kRounding + kOneFlip, "rounding + one threshold flip; the near-plane rule (cull z <= 0.2) is the same in the reference");
  return c;
}

StressCase off_screen_case() {
  StressCase c;
  c.name = "off_screen";
  c.description = "centres thousands to millions of pixels off screen whose extent reaches in: wide blobs, long "
                  "thin needles at shallow angles, a pancake";
  Scene& s = c.scene;
  add(s, 200.0f, 0.0f, 10.0f, 100.0f, 100.0f, 100.0f, kIdentity, 0.8f, 1.0f, 0.3f, 0.3f);  // mean x ~ 2700 px
  add(s, 0.0f, -1e6f, 10.0f, 1e6f, 1e6f, 1e6f, kIdentity, 0.3f, 0.3f, 0.3f, 1.0f);        // mean y ~ -1.3e7 px
  float q[4];
  quaternion_x_to(1.0, 1.0, 0.0, q);  // needle along the diagonal, centre 3700 px off screen
  add(s, -300.0f, -300.0f, 10.0f, 300.0f, 0.01f, 0.01f, q, 0.9f, 0.2f, 1.0f, 0.2f);
  quaternion_x_to(1.0, 0.37, 0.0, q);  // needle at a shallow angle, centre 5000 px to the left
  add(s, -400.0f, -130.0f, 10.0f, 400.0f, 0.02f, 0.01f, q, 0.9f, 1.0f, 1.0f, 0.2f);
  quaternion_x_to(-0.3, 1.0, 0.1, q);  // from below
  add(s, 90.0f, 300.0f, 10.0f, 300.0f, 0.01f, 0.02f, q, 0.8f, 0.2f, 0.8f, 1.0f);
  quaternion_x_to(0.0, 1.0, 0.02, q);  // pancake far below, tilted towards the camera
  add(s, 0.0f, 500.0f, 12.0f, 400.0f, 400.0f, 0.05f, q, 0.6f, 0.8f, 0.5f, 0.2f);
  c.cameras.push_back(axis_camera(256, 256, 90.0));
  set_bounds(c, kRounding + kOneFlip, "rounding + one threshold flip; the footprint is evaluated thousands of pixels from its centre, so "
             "the quadratic form must not cancel");
  return c;
}

StressCase inside_case() {
  StressCase c;
  c.name = "inside_gaussian";
  c.description = "the camera inside large Gaussians (centre just in front), with ordinary ones behind";
  Scene& s = c.scene;
  add(s, 0.1f, 0.0f, 0.5f, 20.0f, 20.0f, 20.0f, kIdentity, 0.5f, 0.9f, 0.6f, 0.3f);
  float q[4];
  quaternion_x_to(1.0, 0.3, 0.4, q);
  add(s, 0.0f, 0.05f, 0.3f, 5.0f, 5.0f, 1.0f, q, 0.3f, 0.2f, 0.4f, 0.9f);
  Rng rng(5);
  for (int k = 0; k < 20; ++k) {
    random_quaternion(rng, q);
    add(s, rng.range(-3, 3), rng.range(-3, 3), rng.range(3, 8), 0.5f, 0.2f, 0.1f, q, 0.9f, rng.uniform(),
        rng.uniform(), rng.uniform());
  }
  c.cameras.push_back(axis_camera(160, 120, 90.0));
  set_bounds(c, kRounding + kOneFlip, "rounding + one threshold flip");
  return c;
}

// A cluster of Gaussians around `origin` seen from nearby, off-axis.
StressCase far_origin_case(const std::string& name, double origin) {
  StressCase c;
  c.name = name;
  char text[200];
  std::snprintf(text, sizeof text,
                "a scene at (%.0e, -%.0e, %.0e) seen from 30 units away (float positions are spaced %.3g there)",
                origin, origin, origin, std::nextafter(static_cast<float>(origin), 1e30f) - static_cast<float>(origin));
  c.description = text;
  Scene& s = c.scene;
  const float ox = static_cast<float>(origin), oy = static_cast<float>(-origin), oz = static_cast<float>(origin);
  Rng rng(11);
  for (int k = 0; k < 60; ++k) {
    float q[4];
    random_quaternion(rng, q);
    // integer offsets: representable at 1e7, where float spacing is 1
    const float dx = std::floor(rng.range(-8, 8)), dy = std::floor(rng.range(-8, 8)), dz = std::floor(rng.range(-8, 8));
    add(s, ox + dx, oy + dy, oz + dz, rng.range(0.3f, 1.5f), rng.range(0.1f, 0.8f), rng.range(0.05f, 0.5f), q,
        rng.range(0.4f, 1.0f), rng.uniform(), rng.uniform(), rng.uniform());
  }
  const double eye[3] = {origin + 7, -origin - 5, origin - 30}, target[3] = {origin, -origin, origin},
               up[3] = {0.1, -1.0, 0.0};
  c.cameras.push_back(look_at(192, 128, 70.0, eye, target, up));
  set_bounds(c, kRounding + kOneFlip, "as a scene at the origin: R (p - c) subtracts first, exactly (Sterbenz), so nothing is lost");
  return c;
}

StressCase depth_range_case() {
  StressCase c;
  c.name = "depth_range";
  c.description = "depths from 0.21 to 1e6 in one frame, near Gaussians in front of far ones";
  Scene& s = c.scene;
  Rng rng(23);
  const float depths[] = {0.21f, 0.3f, 0.5f, 2.0f, 1e2f, 1e4f, 1e5f, 1e6f};
  int k = 0;
  for (float z : depths)
    for (int j = 0; j < 4; ++j, ++k) {
      float q[4], rgb[3];
      random_quaternion(rng, q);
      hue(k / 32.0f, rgb);
      const float x = rng.range(-0.6f, 0.6f) * z, y = rng.range(-0.6f, 0.6f) * z, sc = 0.06f * z;
      add(s, x, y, z, sc, sc * 0.5f, sc * 0.3f, q, rng.range(0.5f, 1.0f), rgb[0], rgb[1], rgb[2]);
    }
  c.cameras.push_back(axis_camera(256, 256, 90.0));
  set_bounds(c, kRounding + kOneFlip, "rounding + one threshold flip");
  return c;
}

StressCase stacked_case() {
  StressCase c;
  c.name = "stacked";
  c.description = "4000 Gaussians stacked on one pixel (depth complexity), low opacities, early termination";
  Scene& s = c.scene;
  Rng rng(29);
  for (int k = 0; k < 4000; ++k) {
    float q[4];
    random_quaternion(rng, q);
    const float z = rng.range(2.0f, 4.0f);
    // The centre projects into pixel (32, 32) of the 64 x 64 image (f = 55.4).
    const float x = (0.5f + rng.range(-0.4f, 0.4f)) * z / 55.4256f, y = (0.5f + rng.range(-0.4f, 0.4f)) * z / 55.4256f;
    add(s, x, y, z, rng.range(0.02f, 0.2f), rng.range(0.01f, 0.05f), rng.range(0.01f, 0.05f), q,
        rng.range(0.005f, 0.05f), rng.uniform(), rng.uniform(), rng.uniform());
  }
  c.cameras.push_back(axis_camera(64, 64, 60.0));
  set_bounds(c, 1e-3 + 2 * kOneFlip, "hundreds of layers per pixel: rounding of T grows with the layer count (1e-3), and more alpha-threshold "
             "decisions per pixel (two flips)");
  return c;
}

StressCase equal_depth_case() {
  StressCase c;
  c.name = "equal_depth";
  c.description = "10000 Gaussians at exactly the same depth, overlapping: the order (and image) must not depend "
                  "on threads or timing (enough of them that the CPU emits them in several chunks)";
  Scene& s = c.scene;
  Rng rng(31);
  for (int k = 0; k < 10000; ++k) {
    float q[4], rgb[3];
    random_quaternion(rng, q);
    hue(rng.uniform(), rgb);
    add(s, rng.range(-0.3f, 0.3f), rng.range(-0.3f, 0.3f), 3.0f, rng.range(0.05f, 0.3f), rng.range(0.02f, 0.1f),
        rng.range(0.02f, 0.1f), q, rng.range(0.05f, 0.6f), rgb[0], rgb[1], rgb[2]);
  }
  c.cameras.push_back(axis_camera(96, 96, 60.0));
  set_bounds(c, 1e-3 + 2 * kOneFlip, "as stacked: many layers per pixel (1e-3 rounding, two flips); ties are broken by index everywhere");
  return c;
}

StressCase opacity_edges_case() {
  StressCase c;
  c.name = "opacity_edges";
  c.description = "opacity 1 (alpha clamped to 0.99), two and three opaque layers (T reaches the 1e-4 stop), "
                  "opacity exactly 1/255, one ulp above and below, 0 and 1e-30";
  Scene& s = c.scene;
  const float tau = kDefaultTau;  // also the blend's alpha cut
  const float opacities[] = {1.0f, 0.99f, tau, std::nextafter(tau, 1.0f), std::nextafter(tau, 0.0f), 0.0f, 1e-30f,
                             2.0f * tau};
  // 64 x 64, f = 32 at z = 2: one world unit is 16 px; centres on pixel centres.
  const float f = 32.0f, z = 2.0f;
  auto world = [&](float pixel) { return (pixel - 31.5f) * z / f; };
  int k = 0;
  for (float o : opacities) {
    const float px = 8.0f + 16.0f * (k % 4), py = 12.0f + 24.0f * (k / 4);
    add(s, world(px), world(py), z, 0.15f, 0.1f, 0.1f, kIdentity, o, 0.9f, 0.8f, 0.2f);
    ++k;
  }
  // Stacks of opaque layers on the centre: after two alpha = 0.99 layers T = 1e-4 exactly
  // in decimal, the stop rule's threshold.
  for (int j = 0; j < 3; ++j) {  // all three centred on pixel (40, 36)
    const float zj = 1.0f + j * 0.5f;
    add(s, (40.0f - 31.5f) * zj / f, (36.0f - 31.5f) * zj / f, zj, 0.3f * zj, 0.3f * zj, 0.3f * zj, kIdentity, 1.0f,
        0.3f * j, 0.5f, 1.0f - 0.3f * j);
  }
  c.cameras.push_back(axis_camera(64, 64, 90.0));
  set_bounds(c, kRounding + kOneFlip, "rounding + one threshold flip: the thresholds are compared against the same float constants");
  return c;
}

// Raw PLY (SH degree 1) with the given records, each 26 floats in the file's property order.
std::string raw_ply(const std::vector<std::vector<float>>& records) {
  std::ostringstream out;
  out << "ply\nformat binary_little_endian 1.0\nelement vertex " << records.size() << "\n";
  for (const char* p : {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"})
    out << "property float " << p << "\n";
  for (int k = 0; k < 9; ++k) out << "property float f_rest_" << k << "\n";
  for (const char* p : {"opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"})
    out << "property float " << p << "\n";
  out << "end_header\n";
  std::string bytes = out.str();
  for (const auto& r : records) bytes.append(reinterpret_cast<const char*>(r.data()), r.size() * sizeof(float));
  return bytes;
}

StressCase degenerate_file_case() {
  StressCase c;
  c.name = "degenerate_file";
  c.description = "a PLY read through load_ply: zero / tiny / huge quaternions, NaN and Inf in every attribute, "
                  "opacity logits +-1e4, log-scales +-100, 50 and 88 (exp near FLT_MAX)";
  // Property indices in the record.
  enum { X = 0, Y, Z, NX, NY, NZ, DC0, DC1, DC2, REST0, OPACITY = 18, S0, S1, S2, R0, R1, R2, R3, COUNT };
  std::vector<std::vector<float>> records;
  Rng rng(37);
  auto healthy = [&](float x, float y, float z) {
    std::vector<float> r(COUNT, 0.0f);
    r[X] = x; r[Y] = y; r[Z] = z;
    for (int k = 0; k < 3; ++k) r[DC0 + k] = rng.range(-1.5f, 1.5f);
    for (int k = 0; k < 9; ++k) r[REST0 + k] = rng.range(-0.3f, 0.3f);
    r[OPACITY] = rng.range(-1.0f, 3.0f);
    r[S0] = std::log(0.3f); r[S1] = std::log(0.15f); r[S2] = std::log(0.05f);
    float q[4];
    random_quaternion(rng, q);
    for (int k = 0; k < 4; ++k) r[R0 + k] = q[k] * 1.7f;  // not normalised, as in real files
    return r;
  };
  for (int gy = 0; gy < 4; ++gy)
    for (int gx = 0; gx < 5; ++gx) records.push_back(healthy(-2.0f + gx, -1.5f + gy, 5.0f));
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  // NaN, +Inf and -Inf in every attribute, one record each (the loader drops them; NaN in
  // the unused normals is harmless).
  for (int attribute = 0; attribute < COUNT; ++attribute)
    for (float bad : {nan, inf, -inf}) {
      auto r = healthy(rng.range(-2, 2), rng.range(-2, 2), 4.0f);
      r[attribute] = bad;
      records.push_back(r);
    }
  auto special = [&](int attribute, float value, float x, float y) {
    auto r = healthy(x, y, 3.0f);
    r[attribute] = value;
    if (attribute == R0) r[R1] = r[R2] = r[R3] = value;  // the whole quaternion
    records.push_back(r);
  };
  special(R0, 0.0f, -1.0f, -1.0f);   // zero quaternion
  special(R0, 1e-30f, 0.0f, -1.0f);  // tiny: |q|^2 underflows in float
  special(R0, 1e30f, 1.0f, -1.0f);   // huge: |q|^2 overflows in float
  special(OPACITY, 1e4f, -1.0f, 0.0f);
  special(OPACITY, -1e4f, 0.0f, 0.0f);
  special(S0, 100.0f, 1.0f, 0.0f);   // exp overflows float: dropped
  special(S1, -100.0f, -1.0f, 1.0f); // exp is subnormal
  special(S2, 88.0f, 0.0f, 1.0f);    // exp = 1.65e38, finite
  special(S0, 50.0f, 1.0f, 1.0f);    // exp = 5e21: the 2D covariance overflows float
  {
    auto r = healthy(0.5f, 0.5f, 3.0f);
    r[S0] = r[S1] = r[S2] = -100.0f;  // all three subnormal
    records.push_back(r);
  }
  c.raw_ply = raw_ply(records);
  c.cameras.push_back(axis_camera(128, 96, 90.0));
  set_bounds(c, kRounding + kOneFlip, "what the loader keeps renders like any scene: rounding + one threshold flip");
  return c;
}

// A cheap scene for the image-size cases: blobs, needles and one Gaussian larger than the
// screen, so that tile ranges span the whole grid.
Scene image_scene() {
  Scene s;
  Rng rng(41);
  for (int k = 0; k < 150; ++k) {
    float q[4], rgb[3];
    random_quaternion(rng, q);
    hue(rng.uniform(), rgb);
    const float z = rng.range(3.0f, 8.0f);
    add(s, rng.range(-0.6f, 0.6f) * z, rng.range(-0.4f, 0.4f) * z, z, rng.range(0.02f, 0.4f),
        rng.range(0.005f, 0.2f), rng.range(0.005f, 0.1f), q, rng.range(0.2f, 1.0f), rgb[0], rgb[1], rgb[2]);
  }
  float q[4];
  quaternion_x_to(1.0, 0.55, 0.0, q);
  add(s, 0.0f, 0.0f, 6.0f, 20.0f, 0.002f, 0.002f, q, 0.9f, 1.0f, 1.0f, 1.0f);  // a hair across the image
  add(s, 0.0f, 0.0f, 30.0f, 40.0f, 40.0f, 40.0f, kIdentity, 0.4f, 0.2f, 0.2f, 0.3f);  // a backdrop
  return s;
}

StressCase image_case(const std::string& name, int width, int height) {
  StressCase c;
  c.name = name;
  c.description = "a " + std::to_string(width) + "x" + std::to_string(height) + " image of a small scene";
  c.scene = image_scene();
  c.cameras.push_back(axis_camera(width, height, 75.0));
  if (static_cast<long long>(width) * height > 512 * 512) {
    c.huge = true;
    // Corners, the centre, a window straddling tile borders at the middle, the last partial row.
    const int w = 48;
    c.windows = {{0, 0, w, w},
                 {width - w, height - w, w, w},
                 {width / 2 - w / 2, height / 2 - w / 2, w, w},
                 {width / 2 - 8, height / 3 - 8, w, w},
                 {width / 3, height - 20, w, 20}};
  }
  set_bounds(c, kRounding + kOneFlip, "rounding + one threshold flip");
  return c;
}

using Factory = std::function<StressCase()>;

const std::vector<std::pair<std::string, Factory>>& factories() {
  static const std::vector<std::pair<std::string, Factory>> list = {
      {"stiff_1e4", [] { return stiff_case("stiff_1e4", 1e4, 1); }},
      {"stiff_1e6", [] { return stiff_case("stiff_1e6", 1e6, 2); }},
      {"stiff_1e8", [] { return stiff_case("stiff_1e8", 1e8, 3); }},
      {"stiff_extreme", stiff_extreme_case},
      {"near_plane", near_plane_case},
      {"off_screen", off_screen_case},
      {"inside_gaussian", inside_case},
      {"far_origin_1e5", [] { return far_origin_case("far_origin_1e5", 1e5); }},
      {"far_origin_1e7", [] { return far_origin_case("far_origin_1e7", 1e7); }},
      {"depth_range", depth_range_case},
      {"stacked", stacked_case},
      {"equal_depth", equal_depth_case},
      {"opacity_edges", opacity_edges_case},
      {"degenerate_file", degenerate_file_case},
      {"image_1x1", [] { return image_case("image_1x1", 1, 1); }},
      {"image_17x9", [] { return image_case("image_17x9", 17, 9); }},
      {"image_8192", [] { return image_case("image_8192", 8192, 8192); }},
      {"image_16384", [] { return image_case("image_16384", 16384, 16384); }},
  };
  return list;
}

}  // namespace

std::vector<std::string> stress_case_names() {
  std::vector<std::string> names;
  for (const auto& f : factories()) names.push_back(f.first);
  return names;
}

StressCase make_stress_case(const std::string& name) {
  for (const auto& f : factories())
    if (f.first == name) return f.second();
  std::string all;
  for (const auto& f : factories()) all += (all.empty() ? "" : ", ") + f.first;
  throw Error("unknown stress case \"" + name + "\" (known: " + all + ")");
}

LoadReport load_stress_scene(StressCase& c) {
  LoadReport report;
  if (c.raw_ply.empty()) return report;
  // A unique name per process and case: tests may run in parallel.
  const auto path = std::filesystem::temp_directory_path() /
                    ("flashgs_stress_" + c.name + "_" + std::to_string(::getpid()) + "_" +
                     std::to_string(reinterpret_cast<std::uintptr_t>(&c)) + ".ply");
  write_file_atomically(path.string(), c.raw_ply);
  try {
    c.scene = load_ply(path.string(), &report);
  } catch (...) {
    std::filesystem::remove(path);
    throw;
  }
  std::filesystem::remove(path);
  return report;
}

}  // namespace flashgs
