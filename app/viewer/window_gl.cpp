// GLFW window creation and event collection.
#include "window_gl.h"

#include <cstdio>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "flashgs/error.h"
#include "gl_headers_gl.h"

namespace flashgs::viewer {
namespace {

void on_glfw_error(int code, const char* text) { std::fprintf(stderr, "flashgs-viewer: GLFW error %d: %s\n", code, text); }

}  // namespace

Window::Window(int width, int height, const std::string& title) {
  glfwSetErrorCallback(on_glfw_error);
  if (!glfwInit()) throw Error("GLFW cannot initialise (no display? set DISPLAY or run under xvfb-run)");
  // GLFW's default context (compatibility profile, highest version): both NVIDIA's GLX and
  // Mesa's llvmpipe give 4.5+ this way; the shaders need only GLSL 3.30.
  glfwWindowHint(GLFW_SCALE_TO_MONITOR, GLFW_TRUE);
  m_window = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!m_window) {
    glfwTerminate();
    throw Error("GLFW cannot create a " + std::to_string(width) + "x" + std::to_string(height) + " window with an OpenGL context");
  }
  glfwMakeContextCurrent(m_window);
  int major = 0, minor = 0;
  const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  if (!version || std::sscanf(version, "%d.%d", &major, &minor) != 2 || major * 10 + minor < 33) {
    const std::string v = version ? version : "unknown";
    glfwDestroyWindow(m_window);
    glfwTerminate();
    throw Error("OpenGL 3.3 or newer is needed; the context offers " + v);
  }
  glfwSetWindowUserPointer(m_window, this);
  glfwSetScrollCallback(m_window, on_scroll);
  glfwSetDropCallback(m_window, on_drop);
  glfwSetKeyCallback(m_window, on_key);
  glfwSetFramebufferSizeCallback(m_window, on_framebuffer_size);
  glfwSetWindowSizeCallback(m_window, on_window_size);
  glfwSetCursorPosCallback(m_window, on_cursor_pos);
  glfwSetWindowFocusCallback(m_window, on_focus);
  glfwSetCursorEnterCallback(m_window, on_cursor_enter);
  glfwSetMouseButtonCallback(m_window, on_mouse_button);
  query_sizes_and_cursor();
  m_focused = glfwGetWindowAttrib(m_window, GLFW_FOCUSED) != 0;
  m_hovered = glfwGetWindowAttrib(m_window, GLFW_HOVERED) != 0;
}

void Window::query_sizes_and_cursor() {
  glfwGetFramebufferSize(m_window, &m_framebuffer_w, &m_framebuffer_h);
  glfwGetWindowSize(m_window, &m_window_w, &m_window_h);
  glfwGetCursorPos(m_window, &m_cursor_x, &m_cursor_y);
}

Window::~Window() {
  if (m_window) glfwDestroyWindow(m_window);
  glfwTerminate();
}

bool Window::should_close() const { return glfwWindowShouldClose(m_window); }
void Window::request_close() { glfwSetWindowShouldClose(m_window, GLFW_TRUE); }

void Window::swap(bool vsync) {
  const int interval = vsync ? 1 : 0;
  if (interval != m_swap_interval) {
    glfwSwapInterval(interval);
    m_swap_interval = interval;
  }
  glfwSwapBuffers(m_window);
}

void Window::resize(int width, int height) {
  glfwSetWindowSize(m_window, width, height);
  // Wait (briefly) until the X server has applied it, so the next frame renders at the new size.
  for (int i = 0; i < 50; ++i) {
    int w = 0, h = 0;
    glfwGetWindowSize(m_window, &w, &h);
    if (w == width && h == height) break;
    glfwWaitEventsTimeout(0.01);
  }
  query_sizes_and_cursor();
}

void Window::poll(double max_wait_seconds) {
  if (max_wait_seconds > 0) glfwWaitEventsTimeout(max_wait_seconds);
  else glfwPollEvents();
}

void Window::framebuffer_size(int* width, int* height) const {
  *width = m_framebuffer_w;
  *height = m_framebuffer_h;
}

float Window::framebuffer_scale() const {
  return m_window_w > 0 ? float(m_framebuffer_w) / float(m_window_w) : 1.0f;
}

float Window::take_scroll() {
  const float s = m_scroll;
  m_scroll = 0;
  return s;
}

std::vector<std::string> Window::take_drops() { return std::move(m_drops); }

std::vector<KeyPress> Window::take_key_presses() { return std::move(m_key_presses); }

void Window::on_key(GLFWwindow* w, int key, int, int action, int mods) {
  if (action == GLFW_PRESS && key >= 0)
    static_cast<Window*>(glfwGetWindowUserPointer(w))->m_key_presses.push_back({key, mods});
}

bool Window::key_down(int key) const { return glfwGetKey(m_window, key) == GLFW_PRESS; }
bool Window::mouse_down(int button) const { return glfwGetMouseButton(m_window, button) == GLFW_PRESS; }
void Window::cursor(double* x, double* y) const {
  *x = m_cursor_x;
  *y = m_cursor_y;
}

void Window::window_size(int* width, int* height) const {
  *width = m_window_w;
  *height = m_window_h;
}

bool Window::take_mouse_pressed(int button) {
  if (button < 0 || button >= kMouseButtons) return false;
  const bool pressed = m_mouse_pressed[button];
  m_mouse_pressed[button] = false;
  return pressed;
}

void Window::on_focus(GLFWwindow* w, int focused) {
  static_cast<Window*>(glfwGetWindowUserPointer(w))->m_focused = focused != 0;
}

void Window::on_cursor_enter(GLFWwindow* w, int entered) {
  static_cast<Window*>(glfwGetWindowUserPointer(w))->m_hovered = entered != 0;
}

void Window::on_mouse_button(GLFWwindow* w, int button, int action, int) {
  auto* self = static_cast<Window*>(glfwGetWindowUserPointer(w));
  if (action == GLFW_PRESS && button >= 0 && button < kMouseButtons) self->m_mouse_pressed[button] = true;
}

void Window::on_framebuffer_size(GLFWwindow* w, int width, int height) {
  auto* self = static_cast<Window*>(glfwGetWindowUserPointer(w));
  self->m_framebuffer_w = width;
  self->m_framebuffer_h = height;
}

void Window::on_window_size(GLFWwindow* w, int width, int height) {
  auto* self = static_cast<Window*>(glfwGetWindowUserPointer(w));
  self->m_window_w = width;
  self->m_window_h = height;
}

void Window::on_cursor_pos(GLFWwindow* w, double x, double y) {
  auto* self = static_cast<Window*>(glfwGetWindowUserPointer(w));
  self->m_cursor_x = x;
  self->m_cursor_y = y;
}

void Window::on_scroll(GLFWwindow* w, double, double dy) {
  static_cast<Window*>(glfwGetWindowUserPointer(w))->m_scroll += static_cast<float>(dy);
}

void Window::on_drop(GLFWwindow* w, int count, const char** paths) {
  auto* self = static_cast<Window*>(glfwGetWindowUserPointer(w));
  for (int i = 0; i < count; ++i) self->m_drops.emplace_back(paths[i]);
}

}  // namespace flashgs::viewer
