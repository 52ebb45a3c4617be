// Procedural scenes and camera paths (see generators.h).
#include "flashgs/generators.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "flashgs/error.h"
#include "flashgs/gaussian_math.h"

namespace flashgs {
namespace {

void push_gaussian(Scene& s, const float p[3], const float scale[3], const float q[4], float opacity,
                   const float rgb[3], const float* rest) {
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (int k = 0; k < 3; ++k) {
    s.positions.push_back(p[k]);
    s.scales.push_back(scale[k]);
    s.sh_dc.push_back((rgb[k] - 0.5f) / gm::kShC0);  // colour -> degree-0 coefficient
  }
  for (int k = 0; k < 4; ++k) s.rotations.push_back(static_cast<float>(q[k] / norm));
  s.opacities.push_back(opacity);
  for (int k = 0; k < s.sh_rest_per_gaussian(); ++k) s.sh_rest.push_back(rest ? rest[k] : 0.0f);
}

void cross(const float a[3], const float b[3], float out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

// Scales v to unit length; false (v unchanged) when it is (nearly) zero.
bool normalize(float v[3]) {
  const float len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  if (!(len > 1e-12f)) return false;
  for (int k = 0; k < 3; ++k) v[k] /= len;
  return true;
}

// Quaternion (w, x, y, z) rotating +x onto the unit vector d.
void quaternion_from_x_to(const float d[3], float q[4]) {
  const float dot = d[0];
  if (dot < -0.9999f) { q[0] = 0; q[1] = 0; q[2] = 1; q[3] = 0; return; }
  // axis = x cross d = (0, -d.z, d.y)
  q[0] = 1.0f + dot;
  q[1] = 0.0f;
  q[2] = -d[2];
  q[3] = d[1];
}

}  // namespace

Scene make_demo_scene(std::size_t count, std::uint32_t seed) {
  Scene s;
  s.sh_degree = 1;
  s.reserve(count);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  const std::size_t knot = count * 2 / 3;
  // A (2, 3) torus knot, radius about 1, centred at the origin, y up (world down is -y).
  for (std::size_t i = 0; i < knot; ++i) {
    const float t = 2.0f * static_cast<float>(M_PI) * static_cast<float>(i) / static_cast<float>(knot);
    auto curve = [](float u, float out[3]) {
      const float r = 0.6f + 0.3f * std::cos(3.0f * u);
      out[0] = r * std::cos(2.0f * u);
      out[1] = 0.3f * std::sin(3.0f * u) + 0.9f;
      out[2] = r * std::sin(2.0f * u);
    };
    float c[3], c2[3];
    curve(t, c);
    curve(t + 1e-3f, c2);
    float tangent[3] = {c2[0] - c[0], c2[1] - c[1], c2[2] - c[2]};
    const float len = std::sqrt(tangent[0] * tangent[0] + tangent[1] * tangent[1] + tangent[2] * tangent[2]);
    for (float& v : tangent) v /= len;
    float p[3];
    for (int k = 0; k < 3; ++k) p[k] = c[k] + 0.035f * normal(rng);
    const float scale[3] = {0.02f + 0.03f * uni(rng), 0.006f + 0.01f * uni(rng), 0.006f + 0.01f * uni(rng)};
    float q[4];
    quaternion_from_x_to(tangent, q);
    const float hue = t / (2.0f * static_cast<float>(M_PI));
    const float rgb[3] = {0.5f + 0.45f * std::cos(6.2832f * hue), 0.5f + 0.45f * std::cos(6.2832f * (hue - 0.33f)),
                          0.5f + 0.45f * std::cos(6.2832f * (hue - 0.67f))};
    // Degree-1 SH: a sheen that changes with the viewing direction.
    float rest[9];
    for (int k = 0; k < 3; ++k)
      for (int ch = 0; ch < 3; ++ch) rest[k * 3 + ch] = 0.25f * tangent[k] * (ch == 2 ? 1.0f : -0.5f);
    push_gaussian(s, p, scale, q, 0.35f + 0.6f * uni(rng), rgb, rest);
  }
  // A checkered floor of flat Gaussians at y = 0.
  const std::size_t floor_count = count - knot;
  const int side = static_cast<int>(std::sqrt(static_cast<double>(floor_count)));
  for (int iz = 0; iz < side; ++iz)
    for (int ix = 0; ix < side; ++ix) {
      const float p[3] = {-2.0f + 4.0f * (ix + uni(rng)) / side, 0.0f, -2.0f + 4.0f * (iz + uni(rng)) / side};
      const float scale[3] = {4.0f / side, 0.002f, 4.0f / side};
      const float q[4] = {1, 0, 0, 0};
      const bool dark = ((static_cast<int>(std::floor(p[0] * 2.0f)) + static_cast<int>(std::floor(p[2] * 2.0f))) & 1) != 0;
      const float grey = dark ? 0.2f : 0.8f;
      const float rgb[3] = {grey, grey, grey * 0.95f};
      push_gaussian(s, p, scale, q, 0.9f, rgb, nullptr);
    }
  return s;
}

Camera look_at_camera(const float eye[3], const float target[3], const float up[3], int width, int height,
                      float fov_degrees) {
  float forward[3];
  for (int k = 0; k < 3; ++k) forward[k] = target[k] - eye[k];
  if (!normalize(forward)) throw Error("look-at camera: the eye is at the target (no view direction)");
  // OpenCV axes: x right, y down, z forward; right = forward x up.
  float right[3];
  cross(forward, up, right);
  if (!normalize(right)) {  // looking along up: any perpendicular will do
    const float other[3] = {up[1], up[2], up[0]};
    cross(forward, other, right);
    normalize(right);
  }
  float down[3];
  cross(forward, right, down);
  // camera-to-world: its columns are the camera axes in world space.
  const float c2w[9] = {right[0], down[0], forward[0], right[1], down[1], forward[1], right[2], down[2], forward[2]};
  const float fx = 0.5f * width / std::tan(0.5f * fov_degrees * static_cast<float>(M_PI) / 180.0f);
  return Camera::from_pose(width, height, fx, fx, c2w, eye);
}

std::vector<Camera> make_orbit_cameras(const float target[3], const float up[3], float radius, float height,
                                       int count, int width, int height_px, float fov_degrees) {
  // An orthonormal frame (e1, e2) of the plane orthogonal to up.
  float u[3] = {up[0], up[1], up[2]};
  normalize(u);
  float e1[3] = {1, 0, 0};
  if (std::abs(u[0]) > 0.9f) { e1[0] = 0; e1[1] = 1; }
  const float d = e1[0] * u[0] + e1[1] * u[1] + e1[2] * u[2];
  for (int k = 0; k < 3; ++k) e1[k] -= d * u[k];
  normalize(e1);
  float e2[3];
  cross(u, e1, e2);
  std::vector<Camera> cameras;
  for (int i = 0; i < count; ++i) {
    const float angle = 2.0f * static_cast<float>(M_PI) * i / count;
    float eye[3];
    for (int k = 0; k < 3; ++k)
      eye[k] = target[k] + radius * (std::cos(angle) * e1[k] + std::sin(angle) * e2[k]) + height * u[k];
    Camera cam = look_at_camera(eye, target, u, width, height_px, fov_degrees);
    cam.name = "orbit_" + std::to_string(i);
    cameras.push_back(cam);
  }
  return cameras;
}

void scene_bounds(const Scene& scene, float lo[3], float hi[3]) {
  for (int k = 0; k < 3; ++k) {
    lo[k] = INFINITY;
    hi[k] = -INFINITY;
  }
  for (std::size_t i = 0; i < scene.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], scene.positions[i * 3 + k]);
      hi[k] = std::max(hi[k], scene.positions[i * 3 + k]);
    }
}

Scene tile_scene(const Scene& scene, int copies) {
  float lo[3], hi[3];
  scene_bounds(scene, lo, hi);
  const float spacing_x = (hi[0] - lo[0]) * 1.05f, spacing_z = (hi[2] - lo[2]) * 1.05f;
  const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(copies))));
  Scene out;
  out.sh_degree = scene.sh_degree;
  out.reserve(scene.size() * copies);
  for (int c = 0; c < copies; ++c) {
    Scene copy = scene;
    const float ox = (c % side - (side - 1) * 0.5f) * spacing_x, oz = (c / side - (side - 1) * 0.5f) * spacing_z;
    for (std::size_t i = 0; i < copy.size(); ++i) {
      copy.positions[i * 3] += ox;
      copy.positions[i * 3 + 2] += oz;
    }
    out.append(copy);
  }
  return out;
}

}  // namespace flashgs
