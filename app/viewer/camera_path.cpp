// Camera path interpolation: uniform Catmull-Rom through the centres, quaternion slerp between rotations.
#include "camera_path.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/quaternion.hpp>

namespace flashgs::viewer {

CameraPath::CameraPath(const std::vector<Camera>& cameras) {
  for (const Camera& c : cameras) m_keys.push_back({pose_of(c), c.horizontal_fov_degrees()});
}

namespace {

// Into [0, 1); not finite -> 0, so no index computed from it can be NaN or out of range.
double wrap01(double t) {
  if (!std::isfinite(t)) return 0.0;
  t -= std::floor(t);
  return t < 1.0 ? t : 0.0;  // t just below 0 can round up to exactly 1
}

}  // namespace

void CameraPath::locate(double t, int* key, float* u) const {
  const int n = static_cast<int>(m_keys.size());
  const double s = wrap01(t) * n;
  const double whole = std::floor(s);
  *key = std::clamp(static_cast<int>(whole), 0, n - 1);
  *u = std::clamp(static_cast<float>(s - whole), 0.0f, 1.0f);
}

double CameraPath::advance(double t, double dt, double seconds_per_camera) const {
  if (m_keys.empty() || !(seconds_per_camera > 0.0) || !std::isfinite(seconds_per_camera) || !std::isfinite(dt))
    return wrap01(t);
  return wrap01(wrap01(t) + dt / (seconds_per_camera * static_cast<double>(m_keys.size())));
}

Pose CameraPath::pose_at(double t) const {
  if (m_keys.empty()) return {};
  const int n = static_cast<int>(m_keys.size());
  int i = 0;
  float u = 0;
  locate(t, &i, &u);
  auto at = [&](int k) -> const Key& { return m_keys[((k % n) + n) % n]; };
  const glm::vec3 p0 = at(i - 1).pose.position, p1 = at(i).pose.position, p2 = at(i + 1).pose.position,
                  p3 = at(i + 2).pose.position;
  // Uniform Catmull-Rom: C1 through every key, so the motion has no kinks at the cameras.
  const float u2 = u * u, u3 = u2 * u;
  Pose pose;
  pose.position = 0.5f * ((2.0f * p1) + (-p0 + p2) * u + (2.0f * p0 - 5.0f * p1 + 4.0f * p2 - p3) * u2 +
                          (-p0 + 3.0f * p1 - 3.0f * p2 + p3) * u3);
  // Smoothstep on the rotation parameter removes the angular-velocity jump at each key.
  const float w = u * u * (3.0f - 2.0f * u);
  const glm::quat q1 = glm::quat_cast(at(i).pose.rotation);
  const glm::quat q2 = glm::quat_cast(at(i + 1).pose.rotation);
  pose.rotation = glm::mat3_cast(glm::normalize(glm::slerp(q1, q2, w)));  // slerp takes the short arc
  return pose;
}

float CameraPath::fov_at(double t) const {
  if (m_keys.empty()) return 60.0f;
  const int n = static_cast<int>(m_keys.size());
  int i = 0;
  float u = 0;
  locate(t, &i, &u);
  return m_keys[i].fov + (m_keys[(i + 1) % n].fov - m_keys[i].fov) * u;
}

}  // namespace flashgs::viewer
