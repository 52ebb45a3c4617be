// KeyScript: a scripted sequence of held keys, mouse drags and window resizes ("W:0.5,D+SHIFT:0.2,MOUSE:120:-40,RESIZE:800:450,WAIT:0.1") for unattended runs.
#pragma once

#include <string>
#include <vector>

#include "camera_controller.h"

namespace flashgs::viewer {

// One frame of scripted input.
struct ScriptFrame {
  NavigationInput nav;
  int resize_width = 0, resize_height = 0;  // > 0: resize the window to this many points
};

class KeyScript {
 public:
  // Throws flashgs::Error on a malformed script, naming the bad step.
  static KeyScript parse(const std::string& text);

  bool done() const { return m_step >= m_steps.size(); }
  // Input for the next frame of `dt` seconds of simulated time; advances the script.
  ScriptFrame next(float dt);
  std::size_t size() const { return m_steps.size(); }

 private:
  struct Step {
    NavigationInput held;  // keys held for `seconds`, or a drag applied in one frame
    float seconds = 0;
    bool is_drag = false;
    int resize_width = 0, resize_height = 0;  // a one-frame window resize
  };
  std::vector<Step> m_steps;
  std::size_t m_step = 0;
  float m_elapsed = 0;  // time spent in the current step
};

}  // namespace flashgs::viewer
