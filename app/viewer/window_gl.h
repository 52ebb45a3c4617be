// Window: the GLFW window and GL context, with the events the viewer polls (scroll, dropped files, size).
#pragma once

#include <string>
#include <vector>

struct GLFWwindow;

namespace flashgs::viewer {

struct KeyPress {
  int key = 0;   // GLFW key code
  int mods = 0;  // GLFW modifier bits held at the press
};

class Window {
 public:
  // Creates a window of width x height screen points with a GL 3.3+ context, current on this
  // thread. Throws flashgs::Error when GLFW or the context cannot be created.
  Window(int width, int height, const std::string& title);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  GLFWwindow* handle() const { return m_window; }
  bool should_close() const;
  void request_close();
  void swap(bool vsync);
  // Asks for a new window size in screen points (the framebuffer follows once the window
  // system has done it).
  void resize(int width, int height);
  // Handles pending events; with `max_wait_seconds` > 0 first waits up to that long for one
  // (glfwPostEmptyEvent from another thread ends the wait).
  void poll(double max_wait_seconds);
  // Framebuffer size in pixels (zero while minimised) and its ratio to window points (high DPI).
  // Sizes and the cursor are kept from GLFW's callbacks: querying them is an X server round
  // trip each (about 0.25 ms a frame on Xvfb for the four the frame loop needs).
  void framebuffer_size(int* width, int* height) const;
  float framebuffer_scale() const;

  // Events gathered since the last take_*() call.
  float take_scroll();
  std::vector<std::string> take_drops();
  // Keys pressed since the last call (GLFW key codes), so that a tap shorter than a slow
  // frame is not lost the way polling glfwGetKey would lose it.
  std::vector<KeyPress> take_key_presses();

  bool key_down(int glfw_key) const;
  bool mouse_down(int glfw_button) const;
  void cursor(double* x, double* y) const;
  // Window size in screen points (zero while minimised).
  void window_size(int* width, int* height) const;
  // Whether the window has the keyboard focus / the pointer is over it (kept from callbacks).
  bool focused() const { return m_focused; }
  bool hovered() const { return m_hovered; }
  // Whether the button went down since the last call: a click shorter than a frame still
  // shows up as held for one frame.
  bool take_mouse_pressed(int glfw_button);

 private:
  static void on_scroll(GLFWwindow* w, double dx, double dy);
  static void on_drop(GLFWwindow* w, int count, const char** paths);
  static void on_key(GLFWwindow* w, int key, int scancode, int action, int mods);
  static void on_framebuffer_size(GLFWwindow* w, int width, int height);
  static void on_window_size(GLFWwindow* w, int width, int height);
  static void on_cursor_pos(GLFWwindow* w, double x, double y);
  static void on_focus(GLFWwindow* w, int focused);
  static void on_cursor_enter(GLFWwindow* w, int entered);
  static void on_mouse_button(GLFWwindow* w, int button, int action, int mods);
  void query_sizes_and_cursor();  // the round trips, once: at creation and after resize()

  GLFWwindow* m_window = nullptr;
  float m_scroll = 0;
  std::vector<std::string> m_drops;
  std::vector<KeyPress> m_key_presses;
  int m_swap_interval = -1;
  int m_framebuffer_w = 0, m_framebuffer_h = 0, m_window_w = 0, m_window_h = 0;
  double m_cursor_x = 0, m_cursor_y = 0;
  bool m_focused = false, m_hovered = false;
  static constexpr int kMouseButtons = 8;  // GLFW_MOUSE_BUTTON_LAST + 1
  bool m_mouse_pressed[kMouseButtons] = {};
};

}  // namespace flashgs::viewer
