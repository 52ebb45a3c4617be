// ImGui drawing of the shortcut table and the hidden-panels hint.
#include "help_overlay_ui.h"

#include <imgui.h>

namespace flashgs::viewer {

void draw_help_window(bool* open, float ui_scale) {
  if (!*open) return;
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(ImVec2(vp->WorkPos.x + vp->WorkSize.x * 0.5f, vp->WorkPos.y + vp->WorkSize.y * 0.5f),
                          ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
  ImGui::SetNextWindowBgAlpha(0.92f);
  if (ImGui::Begin("Keys and mouse (F1)", open, ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoCollapse)) {
    if (ImGui::BeginTable("shortcuts", 2, ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerV)) {
      ImGui::TableSetupColumn("keys", ImGuiTableColumnFlags_WidthFixed, 250.0f * ui_scale);
      ImGui::TableSetupColumn("does");
      ImGui::TableHeadersRow();
      for (const Shortcut& s : kShortcuts) {
        ImGui::TableNextColumn();
        ImGui::TextColored(ImVec4(0.6f, 0.85f, 1.0f, 1), "%s", s.keys);
        ImGui::TableNextColumn();
        ImGui::TextUnformatted(s.action);
      }
      ImGui::EndTable();
    }
  }
  ImGui::End();
}

void draw_hidden_panels_hint(float ui_scale) {
  const char* text = "Tab: panels   F1: help";
  ImDrawList* draw = ImGui::GetForegroundDrawList();
  const ImVec2 size = ImGui::CalcTextSize(text);
  const ImVec2 at(8.0f * ui_scale, 8.0f * ui_scale);
  draw->AddRectFilled(ImVec2(at.x - 4 * ui_scale, at.y - 2 * ui_scale),
                      ImVec2(at.x + size.x + 4 * ui_scale, at.y + size.y + 2 * ui_scale), IM_COL32(0, 0, 0, 140),
                      3.0f * ui_scale);
  draw->AddText(at, IM_COL32(230, 230, 230, 255), text);
}

}  // namespace flashgs::viewer
