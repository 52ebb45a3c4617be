// Camera path interpolation: uniform Catmull-Rom through the centres, quaternion slerp between rotations.
#include "camera_path.h"

#include <cmath>

#include <glm/gtc/quaternion.hpp>

namespace flashgs::viewer {

CameraPath::CameraPath(const std::vector<Camera>& cameras) {
  for (const Camera& c : cameras) m_keys.push_back({pose_of(c), c.horizontal_fov_degrees()});
}

namespace {

double wrap01(double t) {
  t = std::fmod(t, 1.0);
  return t < 0.0 ? t + 1.0 : t;
}

}  // namespace

Pose CameraPath::pose_at(double t) const {
  if (m_keys.empty()) return {};
  const int n = static_cast<int>(m_keys.size());
  const double s = wrap01(t) * n;
  const int i = static_cast<int>(std::floor(s)) % n;
  const float u = static_cast<float>(s - std::floor(s));
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
  const double s = wrap01(t) * n;
  const int i = static_cast<int>(std::floor(s)) % n;
  const float u = static_cast<float>(s - std::floor(s));
  return m_keys[i].fov + (m_keys[(i + 1) % n].fov - m_keys[i].fov) * u;
}

}  // namespace flashgs::viewer
