// The in-app file browser: one folder listed at a time, sorted, folders first.
#include "file_browser_ui.h"

#include <algorithm>
#include <filesystem>

#include <imgui.h>

#include "widget_places_ui.h"

namespace flashgs::viewer {

void FileBrowser::open(const std::string& folder) {
  m_open = true;
  m_just_opened = true;
  std::error_code ec;
  list(std::filesystem::is_directory(folder, ec) ? folder : std::filesystem::current_path(ec).string());
}

void FileBrowser::list(const std::string& folder) {
  namespace fs = std::filesystem;
  std::error_code ec;
  m_folder = fs::absolute(folder, ec).lexically_normal().string();
  m_folders.clear();
  m_files.clear();
  m_error.clear();
  for (fs::directory_iterator it(m_folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.empty() || name[0] == '.') continue;
    std::error_code kind;
    if (it->is_directory(kind)) m_folders.push_back(name);
    else if (it->path().extension() == ".ply") m_files.push_back(name);
  }
  if (ec) m_error = m_folder + ": " + ec.message();
  std::sort(m_folders.begin(), m_folders.end());
  std::sort(m_files.begin(), m_files.end());
}

std::string FileBrowser::draw(float ui_scale) {
  if (!m_open) return "";
  std::string chosen;
  // In the middle of the window, over the panels, opaque: it is a modal choice.
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(ImVec2(vp->WorkPos.x + vp->WorkSize.x * 0.5f, vp->WorkPos.y + vp->WorkSize.y * 0.5f),
                          ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
  ImGui::SetNextWindowSize(ImVec2(460 * ui_scale, 420 * ui_scale), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowBgAlpha(0.97f);
  if (m_just_opened) ImGui::SetNextWindowFocus();
  m_just_opened = false;
  if (ImGui::Begin("Open a scene", &m_open)) {
    ImGui::TextWrapped("%s", m_folder.c_str());
    if (ImGui::Button("Up")) list(std::filesystem::path(m_folder).parent_path().string());
    ImGui::SameLine();
    // A 3DGS training output (point_cloud/iteration_N/...) or a folder holding point_cloud.ply.
    if (ImGui::Button("Open this folder")) chosen = m_folder;
    if (!m_error.empty()) ImGui::TextColored(ImVec4(1, 0.45f, 0.4f, 1), "%s", m_error.c_str());
    ImGui::BeginChild("entries", ImVec2(0, 0), true);
    std::string enter;
    for (const std::string& f : m_folders) {
      if (ImGui::Selectable((f + "/").c_str())) enter = f;
      note_widget_place(("browser: " + f + "/").c_str());
    }
    for (const std::string& f : m_files) {
      if (ImGui::Selectable(f.c_str())) chosen = m_folder + "/" + f;
      note_widget_place(("browser: " + f).c_str());
    }
    ImGui::EndChild();
    if (!enter.empty()) list(m_folder + "/" + enter);
  }
  ImGui::End();
  if (!chosen.empty()) m_open = false;
  return chosen;
}

}  // namespace flashgs::viewer
