// Fly / orbit navigation: rotations about the world-up axis and the camera's right axis, motion scaled by dt.
#include "camera_controller.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

namespace flashgs::viewer {
namespace {

glm::mat3 axis_rotation(const glm::vec3& axis, float angle) {
  return glm::mat3(glm::rotate(glm::mat4(1.0f), angle, glm::normalize(axis)));
}

// Re-orthonormalise so that many small incremental rotations cannot drift into a shear.
glm::mat3 orthonormalised(const glm::mat3& r) {
  glm::vec3 f = glm::normalize(r[2]);
  glm::vec3 x = glm::normalize(r[0] - f * glm::dot(r[0], f));
  glm::vec3 y = glm::cross(f, x);  // OpenCV: x cross y = z, so y = z cross x
  return glm::mat3(x, y, f);
}

// More than any real drag or wheel turn within one frame (a 16K screen crossed four times).
constexpr float kMaxDragPoints = 65536.0f;
constexpr float kMaxScrollSteps = 100.0f;
constexpr float kSpeedStep = 1.25f;      // one +/- press or Ctrl+wheel step
constexpr float kPanPerPoint = 0.0015f;  // pan per window point, in units of the pivot distance

float finite_clamped(float v, float limit) { return std::isfinite(v) ? std::clamp(v, -limit, limit) : 0.0f; }

}  // namespace

NavigationInput sanitized(const NavigationInput& in) {
  NavigationInput out = in;
  out.look_dx = finite_clamped(in.look_dx, kMaxDragPoints);
  out.look_dy = finite_clamped(in.look_dy, kMaxDragPoints);
  out.pan_dx = finite_clamped(in.pan_dx, kMaxDragPoints);
  out.pan_dy = finite_clamped(in.pan_dy, kMaxDragPoints);
  out.scroll = finite_clamped(in.scroll, kMaxScrollSteps);
  out.speed_steps = finite_clamped(in.speed_steps, kMaxScrollSteps);
  return out;
}

bool is_finite(const Pose& pose) {
  for (int c = 0; c < 3; ++c) {
    if (!std::isfinite(pose.position[c])) return false;
    for (int r = 0; r < 3; ++r)
      if (!std::isfinite(pose.rotation[c][r])) return false;
  }
  return true;
}

Pose pose_of(const Camera& camera) {
  Pose pose;
  // camera.rotation is world-to-camera, row-major: its rows are the camera axes in world space.
  for (int axis = 0; axis < 3; ++axis)
    pose.rotation[axis] = glm::vec3(camera.rotation[axis * 3 + 0], camera.rotation[axis * 3 + 1],
                                    camera.rotation[axis * 3 + 2]);
  pose.position = glm::vec3(camera.position[0], camera.position[1], camera.position[2]);
  return pose;
}

void CameraController::reset(const glm::vec3& centre, float extent, const glm::vec3& world_up) {
  const bool centre_ok = std::isfinite(glm::dot(centre, centre));
  m_centre = centre_ok ? centre : glm::vec3(0.0f);
  m_extent = extent > 0.0f && std::isfinite(extent) ? extent : 1.0f;
  const float up_length = glm::length(world_up);
  m_up = up_length > 0.0f && std::isfinite(up_length) ? world_up / up_length : glm::vec3(0.0f, -1.0f, 0.0f);
  m_pivot = m_centre;
  m_snapped_valid = false;
  // Default view: from a distance of two extents, looking at the centre, level with the horizon.
  glm::vec3 any = std::abs(m_up.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 0, 1);
  glm::vec3 forward = glm::normalize(glm::cross(m_up, any));
  forward = glm::normalize(forward - m_up * 0.3f);
  const glm::vec3 right = glm::normalize(glm::cross(m_up, forward) * -1.0f);
  m_pose.rotation = orthonormalised(glm::mat3(right, glm::cross(forward, right), forward));
  m_pose.position = m_centre - forward * (2.0f * m_extent);
  m_orbit_distance = 2.0f * m_extent;
}

void CameraController::snap_to(const Camera& camera) {
  m_pose = pose_of(camera);
  m_snapped = camera;
  m_snapped_valid = true;
  m_snapped_fov = camera.horizontal_fov_degrees();
  place_pivot_ahead();
}

void CameraController::set_pose(const Pose& pose) {
  if (!is_finite(pose)) return;
  m_pose = pose;
  m_snapped_valid = false;
  place_pivot_ahead();
}

void CameraController::place_pivot_ahead() {
  // The pivot is the point ahead of the camera nearest the scene centre: orbiting then keeps
  // the object in view.
  const glm::vec3 forward = m_pose.rotation[2];
  const float along = glm::dot(m_centre - m_pose.position, forward);
  m_orbit_distance = std::max(along, 0.05f * m_extent);
  m_pivot = m_pose.position + forward * m_orbit_distance;
}

void CameraController::set_mode(NavigationMode mode) {
  if (mode == NavigationMode::orbit && m_mode != mode) place_pivot_ahead();
  m_mode = mode;
}

void CameraController::flip_up() {
  m_up = -m_up;
  // Half a turn about the view axis: right and down swap sign, forward stays.
  m_pose.rotation[0] = -m_pose.rotation[0];
  m_pose.rotation[1] = -m_pose.rotation[1];
  m_snapped_valid = false;
}

void CameraController::rotate_view(float yaw, float pitch) {
  // Yaw about the world-up axis (right-hand rule; negative turns toward the camera's right).
  // The axis takes the sign of the camera's own up (-y), so that dragging right turns right
  // even when the view is upside down relative to the chosen world up.
  const glm::vec3 yaw_axis = glm::dot(m_up, -m_pose.rotation[1]) >= 0.0f ? m_up : -m_up;
  glm::mat3 r = axis_rotation(yaw_axis, yaw) * m_pose.rotation;
  // Pitch about the camera's right axis, refused where it would pass over the pole (the view
  // would flip upside down).
  const glm::mat3 pitched = axis_rotation(r[0], pitch) * r;
  const float cos_to_up = glm::dot(pitched[2], m_up);
  if (std::abs(cos_to_up) < 0.995f || std::abs(cos_to_up) < std::abs(glm::dot(r[2], m_up))) r = pitched;
  m_pose.rotation = orthonormalised(r);
}

bool CameraController::update(const NavigationInput& input, float dt, ViewerSettings& settings) {
  if (!std::isfinite(dt) || dt < 0.0f) dt = 0.0f;
  settings.move_speed = kMoveSpeedRange.clamp(settings.move_speed, 1.0f);
  settings.look_sensitivity = kLookSensitivityRange.clamp(settings.look_sensitivity, 0.004f);
  // The last line of defence: whatever the arithmetic did, a non-finite result is undone.
  const Pose pose = m_pose;
  const glm::vec3 pivot = m_pivot;
  const float distance = m_orbit_distance;
  const bool changed = apply(sanitized(input), dt, settings);
  if (!is_finite(m_pose) || !std::isfinite(glm::dot(m_pivot, m_pivot)) || !std::isfinite(m_orbit_distance)) {
    m_pose = pose;
    m_pivot = pivot;
    m_orbit_distance = distance;
    return false;
  }
  return changed;
}

bool CameraController::apply(const NavigationInput& in, float dt, ViewerSettings& settings) {
  if (m_mode != settings.mode) set_mode(settings.mode);
  if (in.speed_steps != 0.0f)
    settings.move_speed = kMoveSpeedRange.clamp(settings.move_speed * std::pow(kSpeedStep, in.speed_steps), 1.0f);
  bool changed = false;
  const float sens = settings.look_sensitivity;
  if (in.look_dx != 0.0f || in.look_dy != 0.0f) {
    rotate_view(-in.look_dx * sens, -in.look_dy * sens);
    changed = true;
  }
  // A drag moves the scene with the pointer, at the pivot's depth: the point under the
  // pointer stays under it (for the default 60-degree view).
  const glm::vec3 pan = -(m_pose.rotation[0] * in.pan_dx + m_pose.rotation[1] * in.pan_dy) *
                        (m_orbit_distance * kPanPerPoint);
  if (m_mode == NavigationMode::fly) {
    if (in.pan_dx != 0.0f || in.pan_dy != 0.0f) {
      m_pose.position += pan;
      changed = true;
    }
    // The wheel dollies along the view by a tenth of the distance to the pivot, at least a
    // hundredth of the scene, so it slows near surfaces and never stalls.
    if (in.scroll != 0.0f) {
      m_pose.position += m_pose.rotation[2] * (in.scroll * std::max(0.1f * m_orbit_distance, 0.01f * m_extent));
      changed = true;
    }
    const glm::vec3 right = m_pose.rotation[0], forward = m_pose.rotation[2];
    glm::vec3 dir = forward * float(in.forward - in.back) + right * float(in.right - in.left) +
                    m_up * float(in.up - in.down);
    if (glm::dot(dir, dir) > 0.0f) {
      const float speed = settings.move_speed * m_extent * (in.fast ? 4.0f : 1.0f);
      m_pose.position += glm::normalize(dir) * (speed * dt);
      changed = true;
    }
    if (changed) place_pivot_ahead();
  } else {
    if (in.pan_dx != 0.0f || in.pan_dy != 0.0f) {
      m_pivot += pan;
      changed = true;
    }
    if (in.scroll != 0.0f) {
      m_orbit_distance = std::clamp(m_orbit_distance * std::pow(0.88f, in.scroll), 1e-4f * m_extent, 1e3f * m_extent);
      changed = true;
    }
    // W/S dolly toward the pivot at a rate proportional to the distance (frame-rate
    // independent), scaled by the speed setting.
    const float dolly = float(in.back - in.forward) * (in.fast ? 4.0f : 1.0f) * settings.move_speed;
    if (dolly != 0.0f) {
      m_orbit_distance = std::clamp(m_orbit_distance * std::exp(dolly * dt), 1e-4f * m_extent, 1e3f * m_extent);
      changed = true;
    }
    if (changed) m_pose.position = m_pivot - m_pose.rotation[2] * m_orbit_distance;
  }
  if (changed) m_snapped_valid = false;
  return changed;
}

void CameraController::frame_scene(float fov_x_degrees, float aspect) {
  const float half_x = 0.5f * kFovRange.clamp(fov_x_degrees, 60.0f) * float(M_PI / 180.0);
  if (!(aspect > 0.0f) || !std::isfinite(aspect)) aspect = 16.0f / 9.0f;
  const float half_y = std::atan(std::tan(half_x) / aspect);
  // The sphere fits the narrower of the two fields.
  const float distance = m_extent / std::sin(std::min(half_x, half_y));
  m_pivot = m_centre;
  m_orbit_distance = distance;
  m_pose.position = m_centre - m_pose.rotation[2] * distance;
  m_snapped_valid = false;
}

bool is_object_sized(const glm::vec3& centre, float extent, const std::vector<Camera>& cameras) {
  if (cameras.empty()) return true;
  // A capture of an object looks at it from around, often from within its own extent (the
  // shared scans' cameras stand 0.65-1.07 extents from the centre): cameras that look at the
  // centre from beyond half an extent, or that stand far outside it.
  const float cos_converging = std::cos(30.0f * float(M_PI / 180.0));
  std::size_t looking_in = 0, far_outside = 0;
  for (const Camera& c : cameras) {
    const glm::vec3 position(c.position[0], c.position[1], c.position[2]);
    const glm::vec3 to_centre = centre - position;
    const float distance = glm::length(to_centre);
    // The view axis in the world: the third row of the world-to-camera rotation.
    const glm::vec3 forward(c.rotation[6], c.rotation[7], c.rotation[8]);
    const bool converging = distance > 0.5f * extent && glm::dot(forward, to_centre) > cos_converging * distance;
    looking_in += converging;
    far_outside += distance > 1.5f * extent;
  }
  return 3 * looking_in >= 2 * cameras.size() || 2 * far_outside > cameras.size();
}

bool CameraController::exact_scene_camera(int width, int height, float fov_x_degrees) const {
  if (!m_snapped_valid || !(std::abs(fov_x_degrees - m_snapped_fov) < 1e-4f) || width <= 0 || height <= 0) return false;
  const double aspect_scene = double(m_snapped.width) / m_snapped.height;
  const double aspect_view = double(width) / height;
  return std::abs(aspect_scene / aspect_view - 1.0) < 1e-3;
}

std::string CameraController::view_description(int index, int width, int height, float fov_x_degrees) const {
  char text[160];
  if (index < 0) return "free view";
  if (!m_snapped_valid) std::snprintf(text, sizeof text, "free view (last camera %d)", index);
  else if (width <= 0 || height <= 0) std::snprintf(text, sizeof text, "on camera %d", index);  // no frame yet
  else if (exact_scene_camera(width, height, fov_x_degrees)) std::snprintf(text, sizeof text, "on camera %d (exact)", index);
  else if (!(std::abs(fov_x_degrees - m_snapped_fov) < 1e-4f)) std::snprintf(text, sizeof text, "on camera %d: pose, other FOV", index);
  else
    std::snprintf(text, sizeof text, "on camera %d: pose, window %.2f:1 vs %.2f:1", index, double(width) / height,
                  double(m_snapped.width) / std::max(m_snapped.height, 1));
  return text;
}

Camera CameraController::render_camera(int width, int height, float fov_x_degrees) const {
  // Same aspect: the scene camera resized exactly as `flashgs render -r WxH` does.
  if (exact_scene_camera(width, height, fov_x_degrees)) return m_snapped.resized(width, height);
  const float fov = kFovRange.clamp(fov_x_degrees, 60.0f) * float(M_PI / 180.0);
  const float f = 0.5f * float(width) / std::tan(0.5f * fov);
  float c2w[9];
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) c2w[row * 3 + col] = m_pose.rotation[col][row];
  const float centre[3] = {m_pose.position.x, m_pose.position.y, m_pose.position.z};
  return Camera::from_pose(width, height, f, f, c2w, centre);
}

}  // namespace flashgs::viewer
