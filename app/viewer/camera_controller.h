// CameraController: fly and orbit navigation of the viewer camera, frame-rate independent (no GL, no window).
#pragma once

#include <string>

#include <vector>

#include <glm/glm.hpp>

#include "flashgs/camera.h"
#include "viewer_settings.h"

namespace flashgs::viewer {

// One frame of navigation input, already translated from the window system.
struct NavigationInput {
  bool forward = false, back = false, left = false, right = false;  // W S A D
  bool down = false, up = false;                                    // Q E
  bool fast = false;                                                // Shift
  float look_dx = 0, look_dy = 0;  // window points dragged with the look button this frame
  float pan_dx = 0, pan_dy = 0;    // window points dragged with the pan button (right/middle)
  float scroll = 0;                // wheel steps this frame: dolly toward (+) or away from the view
  float speed_steps = 0;           // +/- presses and Ctrl+wheel steps: movement speed x1.25 each
};

// A pose in world space: centre and camera-to-world rotation whose columns are the camera's
// x (right), y (down) and z (forward) axes, OpenCV convention like the scene's cameras.
struct Pose {
  glm::vec3 position{0.0f};
  glm::mat3 rotation{1.0f};
};

class CameraController {
 public:
  // `extent` sets the speed and zoom scale (a typical size of the scene in world units);
  // `centre` is the default orbit pivot; `world_up` the axis Q/E and mouse yaw use.
  void reset(const glm::vec3& centre, float extent, const glm::vec3& world_up);
  // Places the camera exactly at a scene camera; render_camera() reproduces it bit for bit at
  // the same aspect ratio until the camera moves.
  void snap_to(const Camera& camera);
  // Moves the camera to `pose` (the field of view is the caller's setting); a pose with a NaN
  // or infinite component is ignored.
  void set_pose(const Pose& pose);
  // Applies one frame of input over `dt` seconds; returns whether the view changed. Non-finite
  // input is ignored and huge drags are clamped: the pose stays finite whatever arrives.
  bool update(const NavigationInput& input, float dt, ViewerSettings& settings);
  // Looks at the scene centre from where the whole scene (a sphere of `extent`) fits the
  // view (`aspect` = width / height), keeping the view direction; the pivot becomes the centre.
  void frame_scene(float fov_x_degrees, float aspect);
  // Inverts the world-up axis and rolls the camera half a turn so the picture turns upright.
  void flip_up();
  void set_mode(NavigationMode mode);

  // The camera to render at width x height (fov clamped to kFovRange; NaN gives 60 degrees).
  Camera render_camera(int width, int height, float fov_x_degrees) const;

  const Pose& pose() const { return m_pose; }
  const glm::vec3& world_up() const { return m_up; }
  const glm::vec3& pivot() const { return m_pivot; }
  // Whether the camera still sits exactly on the snapped scene camera.
  bool on_scene_camera() const { return m_snapped_valid; }
  // Whether render_camera(width, height, fov) is the scene camera itself (same field of view
  // and aspect ratio), not just its pose.
  bool exact_scene_camera(int width, int height, float fov_x_degrees) const;
  // What the View panel says of the view, one short line: "free view", "on camera 22
  // (exact)", or, on the camera's pose and FOV in a window of another shape, "on camera 22:
  // pose, window 1.60:1 vs 1.78:1" (`index` -1: no camera was chosen; width 0: no frame yet).
  std::string view_description(int index, int width, int height, float fov_x_degrees) const;

 private:
  bool apply(const NavigationInput& input, float dt, ViewerSettings& settings);
  void rotate_view(float yaw, float pitch);
  void place_pivot_ahead();

  Pose m_pose;
  glm::vec3 m_up{0.0f, -1.0f, 0.0f};
  glm::vec3 m_centre{0.0f};
  glm::vec3 m_pivot{0.0f};
  float m_extent = 1.0f;
  float m_orbit_distance = 1.0f;
  NavigationMode m_mode = NavigationMode::fly;
  Camera m_snapped;
  bool m_snapped_valid = false;
  float m_snapped_fov = 0.0f;
};

// `input` with every NaN or infinite value zeroed and drags and wheel steps clamped to what a
// hand can do in one frame (a window-system glitch or a script cannot turn into a NaN pose).
NavigationInput sanitized(const NavigationInput& input);
bool is_finite(const Pose& pose);

// Whether a scene is an object seen from around (orbit navigation suits it) rather than a
// space the cameras stand inside (fly): two thirds of the cameras look at `centre` (within 30
// degrees) from beyond half an extent, or most stand farther than 1.5 extents from it.
// Without cameras, an object (generated or single-object scenes).
bool is_object_sized(const glm::vec3& centre, float extent, const std::vector<Camera>& cameras);

// Pose of a scene camera (inverse of Camera's world-to-camera rotation).
Pose pose_of(const Camera& camera);

}  // namespace flashgs::viewer
