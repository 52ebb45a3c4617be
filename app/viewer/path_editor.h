// PathEditor: the keyframed camera path a user authors in the viewer: keys added from the view, replaced, deleted and timed, previewed, saved and loaded.
#pragma once

#include <string>

#include "flashgs/camera.h"
#include "flashgs/keyframe_path.h"

namespace flashgs::viewer {

class PathEditor {
 public:
  // Seconds between a new key and the last one.
  static constexpr double kKeySpacingS = 2.0;

  const KeyframePath& path() const { return m_path; }
  KeyframePath& path() { return m_path; }
  int selected() const { return m_selected; }  // -1: none
  void select(int index);
  // The view as a new key kKeySpacingS after the last (at 0 for the first); it is selected.
  void add(const Camera& view);
  // The selected key takes the view's pose and FOV, keeping its time.
  void replace_selected(const Camera& view);
  void delete_selected();
  // Key `index` moves to `time_s` (>= 0), the keys kept in time order (the selection follows it).
  void set_time(int index, double time_s);
  // Stretches the key times so that the path lasts `duration_s` (> 0) from its first key.
  void set_duration(double duration_s);

  // Writes the path to `file`; loads one (ours or nerfstudio's) replacing the keys. Empty when
  // it worked, else the one-line reason (the path is unchanged).
  std::string save(const std::string& file) const;
  std::string load(const std::string& file);

  // The preview: the path played in the view, from its first key, at real time.
  bool previewing() const { return m_previewing; }
  void start_preview();
  void stop_preview() { m_previewing = false; }
  // Advances the preview by `dt_s` and returns the camera to show (stops after the last key).
  Camera preview_step(double dt_s, int width, int height);

 private:
  KeyframePath m_path;
  int m_selected = -1;
  bool m_previewing = false;
  double m_preview_t = 0;
};

}  // namespace flashgs::viewer
