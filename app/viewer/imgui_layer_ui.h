// ImGuiLayer: Dear ImGui's context with its GLFW and OpenGL 3 backends (init, per-frame begin/end, shutdown).
#pragma once

#include <string>

struct GLFWcursor;

namespace flashgs::viewer {

class Window;

class ImGuiLayer {
 public:
  // `ui_scale` multiplies font and widget sizes (the monitor's content scale on high-DPI screens).
  // The window must outlive the layer. `ini_path`: where ImGui keeps the panel layout (its
  // folder is created); empty: nowhere.
  ImGuiLayer(Window& window, float ui_scale, std::string ini_path);
  ~ImGuiLayer();
  ImGuiLayer(const ImGuiLayer&) = delete;
  ImGuiLayer& operator=(const ImGuiLayer&) = delete;

  void begin_frame();
  void end_frame();  // draws into the current framebuffer
  bool wants_mouse() const;
  bool wants_keyboard() const;
  // A widget is held this frame (a slider or drag box being dragged, a field being edited).
  bool widget_held() const;
  // A popup (a combo's list, the recent scenes) is open.
  bool popup_open() const;
  // Closes every open popup; whether one was open.
  bool close_popups();

 private:
  void update_platform_inputs();

  Window& m_window;
  std::string m_ini_path;  // ImGui keeps the pointer
  double m_last_time = 0;
  int m_cursor_shape = -1;           // the ImGuiMouseCursor last applied
  static constexpr int kCursorShapes = 9;  // ImGuiMouseCursor_COUNT (checked where imgui.h is seen)
  GLFWcursor* m_cursors[kCursorShapes] = {};  // per ImGuiMouseCursor; null: GLFW's default arrow
};

}  // namespace flashgs::viewer
