// Dear ImGui setup over GLFW + OpenGL 3 (the backends come with Debian's libimgui-dev).
#include "imgui_layer_ui.h"

#include <cfloat>
#include <filesystem>
#include <system_error>

#include <imgui.h>
#include <imgui_internal.h>  // ClosePopupToLevel: closing popups from outside their window
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include "window_gl.h"

namespace flashgs::viewer {

ImGuiLayer::ImGuiLayer(Window& window, float ui_scale, std::string ini_path)
    : m_window(window), m_ini_path(std::move(ini_path)) {
  static_assert(kCursorShapes == ImGuiMouseCursor_COUNT, "one GLFW cursor slot per ImGui cursor shape");
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  // Never an imgui.ini beside whatever folder the viewer runs in: the config folder or none.
  // ImGui skips a file it cannot read or write.
  if (!m_ini_path.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(std::filesystem::path(m_ini_path).parent_path(), ec);
  }
  io.IniFilename = m_ini_path.empty() ? nullptr : m_ini_path.c_str();
  ImGui::StyleColorsDark();
  ImGuiStyle& style = ImGui::GetStyle();
  style.WindowRounding = 4.0f;
  style.Colors[ImGuiCol_WindowBg].w = 0.88f;
  if (ui_scale > 1.01f) {
    style.ScaleAllSizes(ui_scale);
    io.FontGlobalScale = ui_scale;
  }
  // true: the backend installs its input callbacks (keys, characters, buttons, wheel, focus)
  // and chains the ones the Window set before.
  ImGui_ImplGlfw_InitForOpenGL(window.handle(), true);
  ImGui_ImplOpenGL3_Init("#version 330");
  m_cursors[ImGuiMouseCursor_TextInput] = glfwCreateStandardCursor(GLFW_IBEAM_CURSOR);
  m_cursors[ImGuiMouseCursor_ResizeNS] = glfwCreateStandardCursor(GLFW_VRESIZE_CURSOR);
  m_cursors[ImGuiMouseCursor_ResizeEW] = glfwCreateStandardCursor(GLFW_HRESIZE_CURSOR);
  m_cursors[ImGuiMouseCursor_Hand] = glfwCreateStandardCursor(GLFW_HAND_CURSOR);
}

ImGuiLayer::~ImGuiLayer() {
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  for (GLFWcursor* c : m_cursors)
    if (c) glfwDestroyCursor(c);
}

// What ImGui_ImplGlfw_NewFrame does, from the Window's cached state: the backend queries the
// window size, framebuffer size, focus and cursor from the X server every frame (four round
// trips) and re-sends the cursor shape; here sizes, focus, hover and cursor come from GLFW's
// callbacks and the cursor shape is sent only when it changes.
void ImGuiLayer::update_platform_inputs() {
  ImGuiIO& io = ImGui::GetIO();
  int w = 0, h = 0, fb_w = 0, fb_h = 0;
  m_window.window_size(&w, &h);
  m_window.framebuffer_size(&fb_w, &fb_h);
  io.DisplaySize = ImVec2(float(w), float(h));
  if (w > 0 && h > 0) io.DisplayFramebufferScale = ImVec2(float(fb_w) / float(w), float(fb_h) / float(h));

  const double now = glfwGetTime();
  io.DeltaTime = m_last_time > 0.0 && now > m_last_time ? float(now - m_last_time) : 1.0f / 60.0f;
  m_last_time = now;

  for (int i = 0; i < IM_ARRAYSIZE(io.MouseDown); ++i)
    io.MouseDown[i] = m_window.take_mouse_pressed(i) || m_window.mouse_down(i);
  if (m_window.focused() || m_window.hovered()) {
    double x = 0, y = 0;
    m_window.cursor(&x, &y);
    io.MousePos = ImVec2(float(x), float(y));
  } else {
    io.MousePos = ImVec2(-FLT_MAX, -FLT_MAX);
  }

  const ImGuiMouseCursor shape = ImGui::GetMouseCursor();
  if (shape != m_cursor_shape && glfwGetInputMode(m_window.handle(), GLFW_CURSOR) != GLFW_CURSOR_DISABLED) {
    if (shape == ImGuiMouseCursor_None) {
      glfwSetInputMode(m_window.handle(), GLFW_CURSOR, GLFW_CURSOR_HIDDEN);
    } else {
      glfwSetCursor(m_window.handle(), shape >= 0 && shape < IM_ARRAYSIZE(m_cursors) ? m_cursors[shape] : nullptr);
      glfwSetInputMode(m_window.handle(), GLFW_CURSOR, GLFW_CURSOR_NORMAL);
    }
    m_cursor_shape = shape;
  }
}

void ImGuiLayer::begin_frame() {
  ImGui_ImplOpenGL3_NewFrame();
  update_platform_inputs();
  ImGui::NewFrame();
}

void ImGuiLayer::end_frame() {
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

bool ImGuiLayer::wants_mouse() const { return ImGui::GetIO().WantCaptureMouse; }
bool ImGuiLayer::wants_keyboard() const { return ImGui::GetIO().WantCaptureKeyboard; }
bool ImGuiLayer::widget_held() const { return ImGui::IsAnyItemActive(); }

bool ImGuiLayer::popup_open() const {
  return ImGui::IsPopupOpen("", ImGuiPopupFlags_AnyPopupId | ImGuiPopupFlags_AnyPopupLevel);
}

bool ImGuiLayer::close_popups() {
  if (!popup_open()) return false;
  ImGui::ClosePopupToLevel(0, true);
  return true;
}

}  // namespace flashgs::viewer
