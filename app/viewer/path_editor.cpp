// Keyframe editing on a KeyframePath: adding, replacing, deleting and retiming keys, the preview clock, the file round trip.
#include "path_editor.h"

#include <algorithm>
#include <cmath>

#include "flashgs/error.h"

namespace flashgs::viewer {

void PathEditor::select(int index) {
  m_selected = index >= 0 && index < int(m_path.keys.size()) ? index : -1;
}

void PathEditor::add(const Camera& view) {
  const double t = m_path.keys.empty() ? 0.0 : m_path.keys.back().time_s + kKeySpacingS;
  m_path.keys.push_back(Keyframe::from_camera(view, t));
  m_selected = int(m_path.keys.size()) - 1;
}

void PathEditor::replace_selected(const Camera& view) {
  if (m_selected < 0) return;
  Keyframe& k = m_path.keys[std::size_t(m_selected)];
  k = Keyframe::from_camera(view, k.time_s);
}

void PathEditor::delete_selected() {
  if (m_selected < 0) return;
  m_path.keys.erase(m_path.keys.begin() + m_selected);
  select(std::min(m_selected, int(m_path.keys.size()) - 1));
  if (m_path.keys.empty()) m_previewing = false;
}

void PathEditor::set_time(int index, double time_s) {
  if (index < 0 || index >= int(m_path.keys.size()) || !std::isfinite(time_s)) return;
  m_path.keys[std::size_t(index)].time_s = std::clamp(time_s, 0.0, 1e6);
  // Re-sorted, the selection following the key (found again by its time and position).
  const Keyframe moved = m_path.keys[std::size_t(index)];
  m_path.sort_keys();
  for (std::size_t i = 0; i < m_path.keys.size(); ++i)
    if (m_path.keys[i].time_s == moved.time_s && std::equal(moved.position, moved.position + 3, m_path.keys[i].position))
      m_selected = int(i);
}

void PathEditor::set_duration(double duration_s) {
  const double old = m_path.duration_s();
  if (!(duration_s > 0) || !std::isfinite(duration_s) || !(old > 0)) return;
  const double start = m_path.keys.front().time_s;
  for (Keyframe& k : m_path.keys) k.time_s = start + (k.time_s - start) * duration_s / old;
}

std::string PathEditor::save(const std::string& file) const {
  if (m_path.keys.empty()) return "camera path: no keyframes to save (add the view with I)";
  try {
    write_camera_path(m_path, file);
  } catch (const std::exception& e) {
    return std::string("camera path not saved: ") + e.what();
  }
  return "";
}

std::string PathEditor::load(const std::string& file) {
  try {
    m_path = read_camera_path(file);
  } catch (const std::exception& e) {
    return std::string("camera path not loaded: ") + e.what();
  }
  m_selected = -1;
  m_previewing = false;
  return "";
}

void PathEditor::start_preview() {
  if (m_path.keys.empty()) return;
  m_previewing = true;
  m_preview_t = m_path.keys.front().time_s;
}

Camera PathEditor::preview_step(double dt_s, int width, int height) {
  if (std::isfinite(dt_s) && dt_s > 0) m_preview_t += dt_s;
  if (m_preview_t >= m_path.keys.back().time_s) m_previewing = false;
  return m_path.camera_at(m_preview_t, width, height);
}

}  // namespace flashgs::viewer
