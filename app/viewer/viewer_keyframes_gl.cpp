// The keyframed camera path in the viewer: the panel's and I's actions, the preview in the view, the path drawn over the scene, and its render into frames.
#include <cstdio>
#include <filesystem>

#include "scene_lines.h"
#include "viewer_app_gl.h"
#include "viewer_panels_ui.h"

namespace flashgs::viewer {

Camera ViewerApp::view_for_key() const {
  const int width = m_last_camera.width > 0 ? m_last_camera.width : 1280;
  const int height = m_last_camera.height > 0 ? m_last_camera.height : 720;
  return m_controller.render_camera(width, height, m_settings.fov_x_degrees);
}

void ViewerApp::show_key_view(int index) {
  const Keyframe& k = m_keys.path().keys[std::size_t(index)];
  const Camera c = m_keys.path().camera_at(k.time_s, 1280, 720);
  m_controller.set_pose(pose_of(c));
  m_settings.fov_x_degrees = k.fov_x_degrees;
  m_camera_index = -1;
  m_playing = false;
}

void ViewerApp::apply_key_actions(const UiActions& a) {
  const auto count = [&] {  // "3 keys, 4.0 s"
    char text[64];
    std::snprintf(text, sizeof text, "%zu keys, %.1f s", m_keys.path().keys.size(), m_keys.path().duration_s());
    return std::string(text);
  };
  if (a.add_key) {
    m_keys.add(view_for_key());
    set_notice("camera path: key " + std::to_string(m_keys.selected()) + " added from the view (" + count() + ")");
  }
  if (a.select_key >= 0) {
    m_keys.select(a.select_key);
    if (m_keys.selected() >= 0) show_key_view(m_keys.selected());
  }
  if (a.replace_key && m_keys.selected() >= 0) {
    m_keys.replace_selected(view_for_key());
    set_notice("camera path: key " + std::to_string(m_keys.selected()) + " now has the view");
  }
  if (a.delete_key && m_keys.selected() >= 0) {
    const int deleted = m_keys.selected();
    m_keys.delete_selected();
    set_notice("camera path: key " + std::to_string(deleted) + " deleted (" + count() + ")");
  }
  if (a.toggle_preview) {
    if (m_keys.previewing()) m_keys.stop_preview();
    else m_keys.start_preview();
    if (m_keys.previewing()) m_playing = false;
    std::fprintf(stderr, "flashgs-viewer: camera path preview %s\n", m_keys.previewing() ? "started" : "stopped");
  }
  if (a.save_keys) {
    const std::string problem = m_keys.save(m_key_fields.file);
    set_notice(problem.empty() ? "camera path saved to " + m_key_fields.file + " (" + count() + ")" : problem);
  }
  if (a.load_keys) load_keys(m_key_fields.file);
  if (!a.render_keys_folder.empty()) start_key_render(a.render_keys_folder);
}

bool ViewerApp::load_keys(const std::string& file) {
  const std::string problem = m_keys.load(file);
  if (!problem.empty()) {
    set_notice(problem);
    return false;
  }
  const KeyframePath& p = m_keys.path();
  char line[256];
  std::snprintf(line, sizeof line, "camera path loaded from %s: %zu keys, %.2f s, %dx%d at %d fps", file.c_str(),
                p.keys.size(), p.duration_s(), p.width, p.height, p.fps);
  set_notice(line);
  return true;
}

bool ViewerApp::preview_keys(float dt) {
  if (!m_keys.previewing()) return false;
  const Camera c = m_keys.preview_step(dt, 1280, 720);
  m_controller.set_pose(pose_of(c));
  m_settings.fov_x_degrees = c.horizontal_fov_degrees();
  m_camera_index = -1;
  if (!m_keys.previewing()) std::fprintf(stderr, "flashgs-viewer: camera path preview ended\n");
  return true;
}

void ViewerApp::key_guides(std::vector<WorldSegment>& world) const {
  const KeyframePath& p = m_keys.path();
  if (p.keys.empty()) return;
  // The keys as frustums (the selected one green), the curve between them in cyan.
  std::vector<Camera> cameras;
  for (const Keyframe& k : p.keys) cameras.push_back(p.camera_at(k.time_s, 160, 90));
  const std::vector<WorldSegment> frustums = camera_frustums(cameras, 0.6f * frustum_depth(), m_keys.selected());
  for (WorldSegment s : frustums) {
    if (s.rgba[1] < 0.9f) s.rgba = {0.95f, 0.35f, 0.95f, 1.0f};  // unselected keys: magenta, not the cameras' orange
    world.push_back(s);
  }
  const int steps = 24 * int(p.keys.size());
  const double start = p.keys.front().time_s, span = p.duration_s();
  auto point = [&](int i) {
    const Camera c = p.camera_at(start + span * i / steps, 16, 9);
    return glm::vec3(c.position[0], c.position[1], c.position[2]);
  };
  for (int i = 0; i < steps && span > 0; ++i) world.push_back({point(i), point(i + 1), {0.3f, 0.95f, 1.0f, 1.0f}});
}

void ViewerApp::start_key_render(const std::string& folder) {
  if (m_keys.path().keys.size() < 2) {
    set_notice("camera path: needs two keys or more to render");
    if (m_scripted) m_exit_code = 2;
    return;
  }
  m_export_keys = m_keys.path();
  m_export_from_keys = true;
  start_path_export(folder, m_export_keys.frame_count());
  if (!m_export.active()) m_export_from_keys = false;
}

}  // namespace flashgs::viewer
