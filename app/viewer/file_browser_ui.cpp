// The in-app file browser: one folder listed at a time (folder_listing.h), a path field, sorting, a training output's iterations.
#include "file_browser_ui.h"

#include <cstdio>
#include <filesystem>

#include <imgui.h>
#include <imgui_stdlib.h>

#include "widget_places_ui.h"

namespace flashgs::viewer {
namespace {

std::string size_text(std::uint64_t bytes) {
  char text[32];
  if (bytes >= 1000000000ull) std::snprintf(text, sizeof text, "%.1f GB", bytes / 1e9);
  else if (bytes >= 1000000ull) std::snprintf(text, sizeof text, "%.1f MB", bytes / 1e6);
  else std::snprintf(text, sizeof text, "%.0f KB", bytes / 1e3);
  return text;
}

}  // namespace

void FileBrowser::open(const std::string& folder) {
  m_open = true;
  m_just_opened = true;
  std::error_code ec;
  list(std::filesystem::is_directory(folder, ec) ? folder : std::filesystem::current_path(ec).string());
}

void FileBrowser::list(const std::string& folder) {
  std::error_code ec;
  m_folder = std::filesystem::absolute(folder, ec).lexically_normal().string();
  if (m_folder.size() > 1 && m_folder.back() == '/') m_folder.pop_back();
  m_typed = m_folder;
  m_error.clear();
  m_entries = list_folder(m_folder, m_sort, &m_error);
}

std::string FileBrowser::draw(float ui_scale) {
  if (!m_open) return "";
  std::string chosen;
  // In the middle of the window, over the panels, opaque: it is a modal choice.
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(ImVec2(vp->WorkPos.x + vp->WorkSize.x * 0.5f, vp->WorkPos.y + vp->WorkSize.y * 0.5f),
                          ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
  ImGui::SetNextWindowSize(ImVec2(520 * ui_scale, 440 * ui_scale), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowBgAlpha(0.97f);
  if (m_just_opened) ImGui::SetNextWindowFocus();
  m_just_opened = false;
  if (ImGui::Begin("Open a scene", &m_open)) {
    // A typed folder is listed, a typed file (or scene folder) opened, with Enter.
    ImGui::SetNextItemWidth(-1);
    if (ImGui::InputText("##browser path", &m_typed, ImGuiInputTextFlags_EnterReturnsTrue)) {
      std::error_code ec;
      if (std::filesystem::is_directory(m_typed, ec)) list(m_typed);
      else chosen = m_typed;
    }
    note_widget_place("browser path");
    if (ImGui::Button("Up")) list(std::filesystem::path(m_folder).parent_path().string());
    ImGui::SameLine();
    // A 3DGS training output (its highest iteration), a SOG set or a folder holding point_cloud.ply.
    if (ImGui::Button("Open this folder")) chosen = m_folder;
    ImGui::SameLine();
    int sort = static_cast<int>(m_sort);
    const char* sorts[] = {"by name", "by size", "newest first"};
    ImGui::SetNextItemWidth(120 * ui_scale);
    if (ImGui::Combo("##sort", &sort, sorts, 3)) {
      m_sort = static_cast<FolderSort>(sort);
      list(m_folder);
    }
    if (!m_error.empty()) ImGui::TextColored(ImVec4(1, 0.45f, 0.4f, 1), "%s", m_error.c_str());
    ImGui::BeginChild("entries", ImVec2(0, 0), true);
    std::string enter;
    for (const FolderEntry& e : m_entries) {
      ImGui::PushID(e.name.c_str());
      if (e.kind == FolderEntry::Kind::scene_file) {
        if (ImGui::Selectable(e.name.c_str())) chosen = m_folder + "/" + e.name;
        note_widget_place(("browser: " + e.name).c_str());
        ImGui::SameLine(ImGui::GetContentRegionAvail().x - 60 * ui_scale);
        ImGui::TextDisabled("%s", size_text(e.bytes).c_str());
      } else {
        if (ImGui::Selectable((e.name + "/").c_str(), false, ImGuiSelectableFlags_AllowItemOverlap)) enter = e.name;
        note_widget_place(("browser: " + e.name + "/").c_str());
        if (e.kind == FolderEntry::Kind::scene_folder) {
          // A scene folder opens as it is, or (a training output) at the iteration chosen.
          ImGui::SameLine(ImGui::GetContentRegionAvail().x * 0.45f);
          if (ImGui::SmallButton("open")) chosen = m_folder + "/" + e.name;
          for (const auto& [n, ply] : e.iterations) {
            ImGui::SameLine();
            if (ImGui::SmallButton(std::to_string(n).c_str())) chosen = ply;
            if (ImGui::IsItemHovered()) ImGui::SetTooltip("iteration %lld", n);
          }
        }
      }
      ImGui::PopID();
    }
    ImGui::EndChild();
    if (!enter.empty()) list(m_folder + "/" + enter);
  }
  ImGui::End();
  if (!chosen.empty()) m_open = false;
  return chosen;
}

}  // namespace flashgs::viewer
