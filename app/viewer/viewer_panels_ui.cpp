// ImGui panels: scene, view, rendering options, compare, statistics; the heat-map legend and comparison labels over the image.
#include "viewer_panels_ui.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <imgui.h>
#include <imgui_stdlib.h>

#include "heatmap_legend.h"
#include "help_overlay_ui.h"

namespace flashgs::viewer {
namespace {

// Widget sizes are written for a 1x screen and multiplied by the UI scale (2 on a 192-dpi X
// screen; 1 on a Retina Mac, where ImGui's points already cover two pixels).
float g_ui = 1.0f;
float ui(float v) { return v * g_ui; }

std::string human_count(double v) {
  char text[32];
  if (v >= 1e6) std::snprintf(text, sizeof text, "%.2fM", v / 1e6);
  else if (v >= 1e4) std::snprintf(text, sizeof text, "%.1fk", v / 1e3);
  else std::snprintf(text, sizeof text, "%.0f", v);
  return text;
}

// Every slider clamps what is typed into it (Ctrl+click) to its range, not just what is dragged.
constexpr ImGuiSliderFlags kClamp = ImGuiSliderFlags_AlwaysClamp;

void scene_panel(const UiModel& m, UiActions& a, std::string& path_buffer) {
  if (!ImGui::CollapsingHeader("Scene", ImGuiTreeNodeFlags_DefaultOpen)) return;
  ImGui::TextWrapped("%s", m.scene_path.c_str());
  ImGui::Text("%s Gaussians, SH degree %d, %d cameras", human_count(double(m.gaussians)).c_str(), m.sh_degree,
              m.camera_count);
  if (!m.scene_note.empty()) ImGui::TextColored(ImVec4(0.9f, 0.8f, 0.4f, 1), "%s", m.scene_note.c_str());
  ImGui::SetNextItemWidth(ui(-140));
  const bool enter = ImGui::InputTextWithHint("##open", "PLY path or folder (or drop a file)", &path_buffer,
                                              ImGuiInputTextFlags_EnterReturnsTrue);
  ImGui::SameLine();
  if ((ImGui::Button("Open") || enter) && !path_buffer.empty()) a.open_path = path_buffer;
  ImGui::SameLine();
  ImGui::BeginDisabled(m.dialog_open);
  if (ImGui::Button("Browse...")) a.open_dialog = true;
  ImGui::EndDisabled();
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) ImGui::SetTooltip("the desktop's file dialog (Ctrl+O)");
  if (m.dialog_open) {
    ImGui::SameLine();
    ImGui::TextDisabled("waiting for %s", m.dialog_tool.empty() ? "the file browser" : m.dialog_tool.c_str());
  }
  if (!m.loading.empty()) {
    ImGui::TextColored(ImVec4(0.5f, 0.8f, 1.0f, 1), "loading %s ...", m.loading.c_str());
    ImGui::SameLine();
    if (ImGui::SmallButton("Cancel")) a.cancel_load = true;
  }
  if (!m.load_error.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.45f, 0.4f, 1));
    ImGui::TextWrapped("%s", m.load_error.c_str());
    ImGui::PopStyleColor();
  }
}

void view_panel(const UiModel& m, ViewerSettings& s, UiActions& a) {
  if (!ImGui::CollapsingHeader("View", ImGuiTreeNodeFlags_DefaultOpen)) return;
  int mode = s.mode == NavigationMode::fly ? 0 : 1;
  ImGui::RadioButton("Fly", &mode, 0);
  ImGui::SameLine();
  ImGui::RadioButton("Orbit", &mode, 1);
  ImGui::SameLine();
  ImGui::TextDisabled("(O)");
  ImGui::SameLine();
  if (ImGui::Button("Frame scene (F)")) a.frame_scene = true;
  s.mode = mode == 0 ? NavigationMode::fly : NavigationMode::orbit;
  if (m.camera_count > 0) {
    if (ImGui::ArrowButton("##prev", ImGuiDir_Left)) a.previous_camera = true;
    ImGui::SameLine();
    int cam = std::max(m.current_camera, 0);
    ImGui::SetNextItemWidth(ui(110));
    if (ImGui::SliderInt("##cam", &cam, 0, m.camera_count - 1, "camera %d", kClamp)) a.snap_camera = cam;
    ImGui::SameLine();
    if (ImGui::ArrowButton("##next", ImGuiDir_Right)) a.next_camera = true;
    ImGui::SameLine();
    if (ImGui::Button(m.playing ? "Stop" : "Play path")) a.toggle_play = true;
    ImGui::SetNextItemWidth(ui(140));
    ImGui::SliderFloat("s per camera", &s.path_seconds_per_camera, kPathSecondsRange.min, kPathSecondsRange.max, "%.1f",
                       kClamp | ImGuiSliderFlags_Logarithmic);
    ImGui::Text(m.on_scene_camera ? "on camera %d (exact)" : "free view (last camera %d)", m.current_camera);
  } else {
    ImGui::TextDisabled("no cameras.json: free navigation");
  }
  ImGui::SliderFloat("FOV (deg)", &s.fov_x_degrees, kFovRange.min, kFovRange.max, "%.1f", kClamp);
  ImGui::SliderFloat("Speed", &s.move_speed, kMoveSpeedRange.min, kMoveSpeedRange.max, "%.3g extents/s",
                     kClamp | ImGuiSliderFlags_Logarithmic);
  ImGui::SliderFloat("Render scale", &s.render_scale, kRenderScaleRange.min, kRenderScaleRange.max, "%.2f", kClamp);
  ImGui::Checkbox("Fewer pixels while moving (slow backends)", &s.adaptive_resolution);
  ImGui::SetNextItemWidth(ui(70));
  if (ImGui::Combo("Up axis", &s.up_axis, kUpAxisNames, kUpAxisCount)) a.up_changed = true;
  ImGui::SameLine();
  if (ImGui::Checkbox("Flip", &s.flip_up)) a.flip_up = true;
  ImGui::SameLine();
  ImGui::TextDisabled("up = (%.2f, %.2f, %.2f)", m.world_up[0], m.world_up[1], m.world_up[2]);
  if (ImGui::Button("Reset view")) a.reset_view = true;
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("position (%.3f, %.3f, %.3f)", m.position[0], m.position[1], m.position[2]);
  ImGui::SameLine();
  ImGui::Checkbox("Grid, axes (G)", &s.show_grid);
  ImGui::SameLine();
  ImGui::BeginDisabled(m.camera_count == 0);
  ImGui::Checkbox("Frustums", &s.show_frustums);
  ImGui::EndDisabled();
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
    ImGui::SetTooltip(m.camera_count ? "the training cameras; click one to jump to it" : "the scene has no cameras");
}

// One optimisation switch: a checkbox greyed out where the backend does not honour it, and a
// tooltip saying what it removes, where the paper has it, its CLI flag and why it is grey.
void switch_checkbox(const RenderSwitch& sw, RenderOptions& o, Backend backend) {
  const bool honoured = sw.honoured_by(backend);
  ImGui::BeginDisabled(!honoured);
  ImGui::Checkbox(sw.ui_name, &(o.*(sw.member)));
  ImGui::EndDisabled();
  if (!ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) return;
  std::string tip = std::string(sw.help) + "\nFlashGS paper: " + sw.paper + "\nCLI: --no-" + sw.cli_name;
  if (!honoured) tip += std::string("\nGreyed out: the ") + backend_name(backend) + " backend ignores it (" +
                        sw.why_ignored + ")";
  else if (o.is_baseline()) tip += "\nGreyed out: the baseline uses none of the optimisations";
  ImGui::SetTooltip("%s", tip.c_str());
}

void render_panel(const UiModel& m, ViewerSettings& s) {
  if (!ImGui::CollapsingHeader("Rendering", ImGuiTreeNodeFlags_DefaultOpen)) return;
  RenderOptions& o = s.options;
  int algo = o.is_baseline() ? 0 : 1;
  ImGui::RadioButton("Baseline (3DGS)", &algo, 0);
  ImGui::SameLine();
  ImGui::RadioButton("Flash", &algo, 1);
  ImGui::SameLine();
  ImGui::TextDisabled("(B)");
  o.algorithm = algo == 0 ? Algorithm::baseline : Algorithm::flash;
  ImGui::BeginDisabled(o.is_baseline());
  // Two columns: the switches that change the Gaussian-tile pairs (geometry) and those that
  // only change how fast the kernels make and blend them.
  if (ImGui::BeginTable("opts", 2, ImGuiTableFlags_SizingStretchSame)) {
    for (const bool geometry : {true, false}) {
      ImGui::TableNextColumn();
      ImGui::TextDisabled(geometry ? "geometry" : "GPU kernels");
      for (const RenderSwitch& sw : kRenderSwitches)
        if (sw.changes_pairs == geometry) switch_checkbox(sw, o, m.backend);
    }
    ImGui::EndTable();
  }
  ImGui::EndDisabled();
  float inv_tau = 1.0f / o.tau;
  char tau_label[64];
  std::snprintf(tau_label, sizeof tau_label, "1/tau (tau %.5f)###tau", o.tau);
  if (ImGui::SliderFloat(tau_label, &inv_tau, 1.0f / kTauRange.max, 1.0f / kTauRange.min, "%.0f",
                         kClamp | ImGuiSliderFlags_Logarithmic))
    o.tau = 1.0f / inv_tau;
  ImGui::SliderInt("SH degree cap", &o.sh_degree_cap, 0, kMaxShDegree, "%d", kClamp);
  ImGui::ColorEdit3("Background", o.background, ImGuiColorEditFlags_NoInputs);
  ImGui::SameLine();
  ImGui::Checkbox("Every frame", &s.continuous);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("re-render every frame (off: only when the view or an option changes)");
  ImGui::SameLine();
  ImGui::Checkbox("VSync", &s.vsync);
}

void compare_panel(const UiModel& m, ViewerSettings& s, UiActions& a) {
  if (!ImGui::CollapsingHeader("Compare", ImGuiTreeNodeFlags_DefaultOpen)) return;
  // The two sides: any two of the configurations compare_mode.h lists.
  auto side = [&](const char* label, int* choice) {
    ImGui::SetNextItemWidth(ui(118));
    if (ImGui::BeginCombo(label, compare_choice_name(*choice).c_str())) {
      for (int c = 0; c < compare_choice_count(); ++c)
        if (ImGui::Selectable(compare_choice_name(c).c_str(), c == *choice)) *choice = c;
      ImGui::EndCombo();
    }
  };
  side("left", &s.compare_left);
  ImGui::SameLine();
  side("right", &s.compare_right);
  ImGui::BeginDisabled(!m.compare_problem.empty());
  if (ImGui::Button("Compare this view (C)")) a.compare = true;
  ImGui::EndDisabled();
  ImGui::SameLine();
  int view = static_cast<int>(s.compare_view);
  const char* views[] = {"numbers only", "split view", "difference"};
  ImGui::SetNextItemWidth(ui(120));
  ImGui::Combo("##view", &view, views, 3);
  s.compare_view = static_cast<CompareView>(view);
  if (!m.compare_problem.empty()) {
    ImGui::TextColored(ImVec4(0.9f, 0.8f, 0.4f, 1), "%s", m.compare_problem.c_str());
    return;
  }
  const CompareResult* c = m.compare;
  if (!c || (!c->valid && c->error.empty())) return;
  if (!c->error.empty()) {
    ImGui::TextColored(ImVec4(1, 0.45f, 0.4f, 1), "%s", c->error.c_str());
    return;
  }
  if (c->stale) {
    ImGui::SameLine();
    ImGui::TextColored(ImVec4(0.9f, 0.8f, 0.4f, 1), "(view changed: C again)");
  }
  ImGui::Text("%s (right) vs %s (left) at %dx%d", c->right_label.c_str(), c->left_label.c_str(), c->width, c->height);
  if (std::isinf(c->difference.psnr_db)) ImGui::Text("PSNR: identical   max abs: 0");
  else ImGui::Text("PSNR %.2f dB   max abs %.5f (%.2f/255)", c->difference.psnr_db, c->difference.max_abs,
                   c->difference.max_abs * 255.0);
  ImGui::Text("pixels off by > 1/255: %.4f%%", 100.0 * c->difference.fraction_over_1_255);
  if (s.compare_view == CompareView::difference) ImGui::Text("difference image: |error| x %.0f", m.difference_factor);
  ImGui::Text("speed-up %.2fx   pair reduction %.1f%%", c->speed_up(), 100.0 * c->pair_reduction());
  if (ImGui::BeginTable("cmp", 3, ImGuiTableFlags_BordersInnerH)) {
    ImGui::TableSetupColumn("");
    ImGui::TableSetupColumn("left");
    ImGui::TableSetupColumn("right");
    ImGui::TableHeadersRow();
    ImGui::TableNextRow();
    ImGui::TableNextColumn(); ImGui::Text("frame ms");
    ImGui::TableNextColumn(); ImGui::Text("%.2f", c->left_ms);
    ImGui::TableNextColumn(); ImGui::Text("%.2f", c->right_ms);
    ImGui::TableNextRow();
    ImGui::TableNextColumn(); ImGui::Text("wall ms");
    ImGui::TableNextColumn(); ImGui::Text("%.2f", c->left_wall_ms);
    ImGui::TableNextColumn(); ImGui::Text("%.2f", c->right_wall_ms);
    ImGui::TableNextRow();
    ImGui::TableNextColumn(); ImGui::Text("kv pairs");
    ImGui::TableNextColumn(); ImGui::Text("%s", human_count(double(c->left_kv)).c_str());
    ImGui::TableNextColumn(); ImGui::Text("%s", human_count(double(c->right_kv)).c_str());
    ImGui::EndTable();
  }
}

void overlay_panel(const UiModel& m, ViewerSettings& s, UiActions& a, std::string& export_folder) {
  if (!ImGui::CollapsingHeader("Overlay, screenshots, export", ImGuiTreeNodeFlags_DefaultOpen)) return;
  ImGui::Checkbox("Tile heat map (H)", &s.heatmap);
  ImGui::SameLine();
  ImGui::Checkbox("log", &s.heatmap_log);
  ImGui::SameLine();
  ImGui::Checkbox("lock max", &s.heatmap_lock_max);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("keep the scale's maximum while switching configurations, so colours compare");
  ImGui::SetNextItemWidth(ui(120));
  ImGui::SliderFloat("opacity", &s.heatmap_opacity, kHeatmapOpacityRange.min, kHeatmapOpacityRange.max, "%.2f", kClamp);
  ImGui::SameLine();
  ImGui::Checkbox("in screenshots", &s.screenshot_overlay);
  ImGui::SetNextItemWidth(ui(-90));
  ImGui::InputTextWithHint("##shotdir", "screenshot folder", &s.screenshot_folder);
  ImGui::SameLine();
  if (ImGui::Button("Save (F12)")) a.screenshot = true;
  if (!m.status.empty()) ImGui::TextWrapped("%s", m.status.c_str());
  if (m.export_total > 0) {
    ImGui::ProgressBar(float(m.export_done) / float(m.export_total), ImVec2(ui(-70), 0));
    ImGui::SameLine();
    if (ImGui::Button("Cancel##export")) a.cancel_export = true;
  } else if (m.camera_count > 0) {
    ImGui::SetNextItemWidth(ui(-90));
    ImGui::InputTextWithHint("##export", "folder for the path's frames", &export_folder);
    ImGui::SameLine();
    if (ImGui::Button("Export path") && !export_folder.empty()) a.export_folder = export_folder;
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("one loop of the camera path as frame_00000.png, ...; also path.mp4 when ffmpeg is on PATH");
  }
}

void stats_window(const UiModel& m) {
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(ImVec2(vp->WorkPos.x + vp->WorkSize.x - ui(10), vp->WorkPos.y + ui(10)),
                          ImGuiCond_Always, ImVec2(1, 0));  // anchored top right as it grows and shrinks
  // In a small window the panels would cover the picture: statistics start folded there.
  ImGui::SetNextWindowCollapsed(vp->WorkSize.x < ui(1000), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowBgAlpha(0.75f);
  // The title keeps the active path and the frame rate in view when the window is folded.
  char title[256];
  std::snprintf(title, sizeof title, "%.1f FPS | %s###Statistics", m.fps, m.frame_path.c_str());
  ImGui::SetNextWindowSizeConstraints(ImVec2(ui(380), 0), ImVec2(vp->WorkSize.x, vp->WorkSize.y));
  ImGui::Begin(title, nullptr, ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoMove);
  ImGui::TextColored(ImVec4(0.5f, 0.9f, 0.6f, 1), "%s", m.frame_path.c_str());
  if (!m.frame_path_note.empty()) ImGui::TextDisabled("%s", m.frame_path_note.c_str());
  ImGui::Text("%.1f FPS   render %dx%d", m.fps, m.render_width, m.render_height);
  if (const FrameStats* st = m.stats) {
    ImGui::Text("kv pairs %s   visible %s / %s", human_count(double(st->kv_pairs)).c_str(),
                human_count(double(st->visible)).c_str(), human_count(double(st->gaussians)).c_str());
    ImGui::Text("culled: near %s  off-screen %s  low-opacity %s  degenerate %s",
                human_count(double(st->culled_near)).c_str(), human_count(double(st->culled_offscreen)).c_str(),
                human_count(double(st->culled_low_opacity)).c_str(), human_count(double(st->culled_degenerate)).c_str());
    if (st->device_peak_bytes > 0)
      ImGui::Text("device memory %.1f MB (peak %.1f MB)", st->device_memory_bytes / 1e6, st->device_peak_bytes / 1e6);
    else
      ImGui::TextDisabled("device memory: none (CPU backend)");
    ImGui::Text("project %.2f  emit %.2f  sort %.2f  ranges %.2f  blend %.2f ms", st->times.project_ms,
                st->times.emit_ms, st->times.sort_ms, st->times.ranges_ms, st->times.blend_ms);
  }
  if (const StatsHistory* h = m.history) {
    const StatsHistory::Series shown[] = {StatsHistory::kFrame, StatsHistory::kRender, StatsHistory::kProject,
                                          StatsHistory::kEmit, StatsHistory::kSort, StatsHistory::kBlend};
    for (StatsHistory::Series s : shown) {
      int count = 0, offset = 0;
      const float* values = h->series(s, &count, &offset);
      char overlay[64];
      std::snprintf(overlay, sizeof overlay, "%s %.2f ms (max %.2f)", StatsHistory::name(s), h->mean(s), h->max(s));
      ImGui::PlotLines("##h", values, count, offset, overlay, 0.0f, float(h->max(s) * 1.1 + 1e-3),
                       ImVec2(ui(260), ui(s == StatsHistory::kFrame ? 40 : 24)));
    }
  }
  ImGui::End();
}

// The legend bar's caption and tick labels (the bar itself is the heat-map shader's, at
// legend_rect_points).
void legend_labels(const UiModel& m, const ViewerSettings& s) {
  ImDrawList* draw = ImGui::GetForegroundDrawList();
  const float* r = m.legend_rect_points;
  const ImU32 white = IM_COL32(255, 255, 255, 255);
  const float line = ImGui::GetTextLineHeight();
  // Caption above the bar, tick marks and values below it, each on a dark backing that
  // leaves the bar's colours (the GL pass under this) untouched.
  const ImU32 backing = IM_COL32(0, 0, 0, 160);
  draw->AddRectFilled(ImVec2(r[0] - ui(6), r[1] - line - ui(6)), ImVec2(r[2] + ui(6), r[1]), backing, ui(3.0f));
  draw->AddRectFilled(ImVec2(r[0] - ui(16), r[3]), ImVec2(r[2] + ui(16), r[3] + line + ui(6)), backing, ui(3.0f));
  const std::string caption = legend_caption(m.tile_size, s.heatmap_log, s.heatmap_lock_max);
  draw->AddText(ImVec2(r[0], r[1] - line - ui(3)), white, caption.c_str());
  for (const LegendTick& t : legend_ticks(m.heatmap_max, s.heatmap_log)) {
    const float x = r[0] + t.position * (r[2] - r[0]);
    draw->AddLine(ImVec2(x, r[3]), ImVec2(x, r[3] + ui(4)), white, ui(1.0f));
    const std::string label = human_count(double(t.value));
    const float w = ImGui::CalcTextSize(label.c_str()).x;
    draw->AddText(ImVec2(x - 0.5f * w, r[3] + ui(4)), white, label.c_str());
  }
}

// Which configuration is on which side, and the difference image's magnification.
void compare_labels(const UiModel& m, const ViewerSettings& s) {
  const CompareResult* c = m.compare;
  if (!m.compare_shown || !c) return;
  ImDrawList* draw = ImGui::GetForegroundDrawList();
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  const float y = vp->WorkPos.y + vp->WorkSize.y - ImGui::GetTextLineHeight() - ui(40);
  auto label = [&](float x, const std::string& text) {
    const ImVec2 size = ImGui::CalcTextSize(text.c_str());
    draw->AddRectFilled(ImVec2(x - ui(4), y - ui(2)), ImVec2(x + size.x + ui(4), y + size.y + ui(2)),
                        IM_COL32(0, 0, 0, 170), ui(3));
    draw->AddText(ImVec2(x, y), IM_COL32(255, 255, 255, 255), text.c_str());
  };
  char text[160];
  if (s.compare_view == CompareView::difference) {
    std::snprintf(text, sizeof text, "|%s - %s| x %.0f", c->right_label.c_str(), c->left_label.c_str(), m.difference_factor);
    label(vp->WorkPos.x + ui(12), text);
    return;
  }
  const float at = vp->WorkPos.x + m.divider * vp->WorkSize.x;
  label(at - ui(12) - ImGui::CalcTextSize(c->left_label.c_str()).x, c->left_label);
  label(at + ui(12), c->right_label);
}

}  // namespace

void draw_panels(const UiModel& m, ViewerSettings& s, UiActions& a, std::string& path_buffer, std::string& export_folder) {
  g_ui = m.ui_scale;
  ImGui::SetNextWindowPos(ImVec2(ui(10), ui(10)), ImGuiCond_FirstUseEver);
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowSizeConstraints(ImVec2(ui(300), ui(100)), ImVec2(ui(600), std::max(ui(120), vp->WorkSize.y - ui(20))));
  ImGui::SetNextWindowSize(ImVec2(ui(380), 0), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowBgAlpha(0.85f);
  ImGui::Begin("flashgs-viewer");
  ImGui::PushItemWidth(ImGui::GetWindowWidth() * 0.5f);  // leaves room for the labels
  scene_panel(m, a, path_buffer);
  view_panel(m, s, a);
  render_panel(m, s);
  compare_panel(m, s, a);
  overlay_panel(m, s, a, export_folder);
  if (ImGui::Button("Keys and mouse (F1)")) s.show_help = !s.show_help;
  ImGui::SameLine();
  ImGui::TextDisabled("Tab hides the panels");
  ImGui::PopItemWidth();
  ImGui::End();
  stats_window(m);
}

void draw_overlays(const UiModel& m, ViewerSettings& s) {
  g_ui = m.ui_scale;
  if (s.heatmap && !m.compare_shown) legend_labels(m, s);
  compare_labels(m, s);
  draw_help_window(&s.show_help, m.ui_scale);
  if (!s.show_ui) draw_hidden_panels_hint(m.ui_scale);
}

}  // namespace flashgs::viewer
