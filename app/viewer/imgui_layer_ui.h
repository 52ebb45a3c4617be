// ImGuiLayer: Dear ImGui's context with its GLFW and OpenGL 3 backends (init, per-frame begin/end, shutdown).
#pragma once

struct GLFWwindow;

namespace flashgs::viewer {

class ImGuiLayer {
 public:
  // `ui_scale` multiplies font and widget sizes (the monitor's content scale on high-DPI screens).
  ImGuiLayer(GLFWwindow* window, float ui_scale);
  ~ImGuiLayer();
  ImGuiLayer(const ImGuiLayer&) = delete;
  ImGuiLayer& operator=(const ImGuiLayer&) = delete;

  void begin_frame();
  void end_frame();  // draws into the current framebuffer
  bool wants_mouse() const;
  bool wants_keyboard() const;
};

}  // namespace flashgs::viewer
