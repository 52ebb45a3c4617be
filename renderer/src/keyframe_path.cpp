// Keyframe path interpolation: Catmull-Rom through the key positions, quaternion slerp between their rotations, the FOV linear, optional ease in/out over the whole path.
#include "flashgs/keyframe_path.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "flashgs/error.h"

namespace flashgs {
namespace {

using Quat = std::array<double, 4>;  // w, x, y, z

// The unit quaternion of a row-major rotation matrix (Shepperd's method: the largest of the
// four candidates is divided by, so none is near zero).
Quat quat_of(const float* m) {
  const double t = double(m[0]) + m[4] + m[8];
  Quat q;
  if (t > 0) {
    const double s = 2.0 * std::sqrt(1.0 + t);
    q = {0.25 * s, (m[7] - m[5]) / s, (m[2] - m[6]) / s, (m[3] - m[1]) / s};
  } else if (m[0] > m[4] && m[0] > m[8]) {
    const double s = 2.0 * std::sqrt(1.0 + m[0] - m[4] - m[8]);
    q = {(m[7] - m[5]) / s, 0.25 * s, (m[1] + m[3]) / s, (m[2] + m[6]) / s};
  } else if (m[4] > m[8]) {
    const double s = 2.0 * std::sqrt(1.0 + m[4] - m[0] - m[8]);
    q = {(m[2] - m[6]) / s, (m[1] + m[3]) / s, 0.25 * s, (m[5] + m[7]) / s};
  } else {
    const double s = 2.0 * std::sqrt(1.0 + m[8] - m[0] - m[4]);
    q = {(m[3] - m[1]) / s, (m[2] + m[6]) / s, (m[5] + m[7]) / s, 0.25 * s};
  }
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double& v : q) v /= n;
  return q;
}

void matrix_of(const Quat& q, float* m) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                       2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                       2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
  for (int i = 0; i < 9; ++i) m[i] = static_cast<float>(r[i]);
}

// Along the short arc from a to b.
Quat slerp(const Quat& a, Quat b, double u) {
  double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  if (d < 0) {
    for (double& v : b) v = -v;
    d = -d;
  }
  double wa = 1 - u, wb = u;
  if (d < 0.9995) {  // else nearly equal: linear, normalised below
    const double angle = std::acos(std::min(d, 1.0));
    wa = std::sin((1 - u) * angle) / std::sin(angle);
    wb = std::sin(u * angle) / std::sin(angle);
  }
  Quat q;
  for (int i = 0; i < 4; ++i) q[i] = wa * a[i] + wb * b[i];
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double& v : q) v /= n;
  return q;
}

}  // namespace

Keyframe Keyframe::from_camera(const Camera& camera, double time_s) {
  Keyframe k;
  k.time_s = time_s;
  for (int i = 0; i < 3; ++i) k.position[i] = camera.position[i];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) k.camera_to_world[r * 3 + c] = camera.rotation[c * 3 + r];
  k.fov_x_degrees = camera.horizontal_fov_degrees();
  return k;
}

const char* easing_name(PathEasing easing) { return easing == PathEasing::linear ? "linear" : "ease_in_out"; }

int KeyframePath::frame_count() const {
  if (keys.empty() || fps <= 0) return 0;
  return static_cast<int>(std::floor(duration_s() * fps + 1e-6)) + 1;
}

double KeyframePath::frame_time(int index) const {
  return (keys.empty() ? 0.0 : keys.front().time_s) + double(index) / double(std::max(fps, 1));
}

void KeyframePath::sort_keys() {
  std::stable_sort(keys.begin(), keys.end(), [](const Keyframe& a, const Keyframe& b) { return a.time_s < b.time_s; });
}

Camera KeyframePath::camera_at(double time_s, int width, int height) const {
  if (keys.empty()) throw Error("camera path: no keyframes");
  const int n = static_cast<int>(keys.size());
  const double start = keys.front().time_s, end = keys.back().time_s;
  double t = std::isfinite(time_s) ? std::clamp(time_s, start, end) : start;
  if (easing == PathEasing::ease_in_out && end > start) {
    const double s = (t - start) / (end - start);
    t = start + (end - start) * s * s * (3 - 2 * s);
  }
  // The segment [i, i + 1] holding t (the last key's own time: the last segment's end).
  int i = 0;
  while (i + 1 < n - 1 && keys[i + 1].time_s <= t) ++i;
  const Keyframe& a = keys[i];
  const Keyframe& b = keys[std::min(i + 1, n - 1)];
  const double span = b.time_s - a.time_s;
  const double u = span > 0 ? std::clamp((t - a.time_s) / span, 0.0, 1.0) : (t >= b.time_s && n > 1 ? 1.0 : 0.0);
  // Catmull-Rom: the neighbours beyond the ends are the ends mirrored, so the curve runs
  // straight out of the first key and into the last.
  float position[3];
  for (int k = 0; k < 3; ++k) {
    const double p1 = a.position[k], p2 = b.position[k];
    const double p0 = i > 0 ? keys[i - 1].position[k] : 2 * p1 - p2;
    const double p3 = i + 2 < n ? keys[i + 2].position[k] : 2 * p2 - p1;
    const double u2 = u * u, u3 = u2 * u;
    position[k] = static_cast<float>(0.5 * (2 * p1 + (-p0 + p2) * u + (2 * p0 - 5 * p1 + 4 * p2 - p3) * u2 +
                                            (-p0 + 3 * p1 - 3 * p2 + p3) * u3));
  }
  float c2w[9];
  if (u == 0.0) std::copy(a.camera_to_world, a.camera_to_world + 9, c2w);
  else if (u == 1.0) std::copy(b.camera_to_world, b.camera_to_world + 9, c2w);
  else matrix_of(slerp(quat_of(a.camera_to_world), quat_of(b.camera_to_world), u), c2w);
  const double fov = a.fov_x_degrees + (b.fov_x_degrees - a.fov_x_degrees) * u;
  const float f = static_cast<float>(0.5 * width / std::tan(0.5 * fov * M_PI / 180.0));
  return Camera::from_pose(width, height, f, f, c2w, position);
}

}  // namespace flashgs
