// ImGui panels: scene, view, rendering options, compare, statistics; the heat-map legend and comparison labels over the image.
#include "viewer_panels_ui.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include <imgui.h>
#include <imgui_stdlib.h>

#include "count_text.h"
#include "flashgs/frame_memory.h"
#include "flashgs/lod_tint.h"
#include "scene_loader.h"
#include "heatmap_legend.h"
#include "help_overlay_ui.h"
#include "widget_places_ui.h"

namespace flashgs::viewer {
namespace {

// Widget sizes are written for a 1x screen and multiplied by the UI scale (2 on a 192-dpi X
// screen; 1 on a Retina Mac, where ImGui's points already cover two pixels).
float g_ui = 1.0f;
float ui(float v) { return v * g_ui; }
// The main panel's right edge this frame (the status line stays right of it).
float g_panel_right = 0;

// Every slider clamps what is typed into it (Ctrl+click) to its range, not just what is dragged.
constexpr ImGuiSliderFlags kClamp = ImGuiSliderFlags_AlwaysClamp;

std::string megabytes(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.0f MB", double(bytes) / 1e6);
  return text;
}

// Coloured text wrapped at the window's edge (a long path or message is never cut off).
void colored_wrapped(const ImVec4& colour, const std::string& text) {
  ImGui::PushStyleColor(ImGuiCol_Text, colour);
  ImGui::TextWrapped("%s", text.c_str());
  ImGui::PopStyleColor();
}

// A checkbox that can be greyed out: then its tick is grey too (ImGui only dims the bright
// tick, which still reads as "on and active").
bool greyed_checkbox(const char* label, bool* value, bool enabled) {
  ImGui::BeginDisabled(!enabled);
  if (!enabled) ImGui::PushStyleColor(ImGuiCol_CheckMark, ImGui::GetStyle().Colors[ImGuiCol_TextDisabled]);
  const bool changed = ImGui::Checkbox(label, value);
  if (!enabled) ImGui::PopStyleColor();
  ImGui::EndDisabled();
  return changed;
}

// Call after Begin: a window that a resize (or a drag) left partly outside the viewport comes
// back inside it, as far as it fits. `name` logs its bottom-right corner (--log-input).
void keep_inside_viewport(const char* name) {
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  const ImVec2 pos = ImGui::GetWindowPos(), size = ImGui::GetWindowSize();
  const ImVec2 inside(std::clamp(pos.x, vp->WorkPos.x, std::max(vp->WorkPos.x, vp->WorkPos.x + vp->WorkSize.x - size.x)),
                      std::clamp(pos.y, vp->WorkPos.y, std::max(vp->WorkPos.y, vp->WorkPos.y + vp->WorkSize.y - size.y)));
  if (inside.x != pos.x || inside.y != pos.y) ImGui::SetWindowPos(inside);
  note_drawn_place(name, inside.x + size.x, inside.y + size.y, inside.x + size.x, inside.y + size.y);
}

// A progress bar; with `fraction` < 0 (not known) a block sliding along it, so that the
// window visibly works while a reader reports nothing.
void progress_bar(float fraction, const std::string& overlay, double elapsed_s) {
  if (fraction >= 0.0f) {
    ImGui::ProgressBar(std::min(fraction, 1.0f), ImVec2(-1, 0), overlay.c_str());
    return;
  }
  const ImVec2 size(ImGui::GetContentRegionAvail().x, ImGui::GetFrameHeight());
  const ImVec2 p = ImGui::GetCursorScreenPos();
  ImDrawList* draw = ImGui::GetWindowDrawList();
  draw->AddRectFilled(p, ImVec2(p.x + size.x, p.y + size.y), ImGui::GetColorU32(ImGuiCol_FrameBg),
                      ImGui::GetStyle().FrameRounding);
  const float block = size.x * 0.25f;
  const float t = float(std::fmod(elapsed_s / 1.5, 1.0));  // one sweep every 1.5 s
  const float x0 = p.x + (size.x - block) * (t < 0.5f ? 2 * t : 2 - 2 * t);
  draw->AddRectFilled(ImVec2(x0, p.y), ImVec2(x0 + block, p.y + size.y), ImGui::GetColorU32(ImGuiCol_PlotHistogram),
                      ImGui::GetStyle().FrameRounding);
  const ImVec2 text_size = ImGui::CalcTextSize(overlay.c_str());
  draw->AddText(ImVec2(p.x + (size.x - text_size.x) * 0.5f, p.y + (size.y - text_size.y) * 0.5f),
                ImGui::GetColorU32(ImGuiCol_Text), overlay.c_str());
  ImGui::Dummy(size);
}

// The background load: file, bar, bytes, Gaussians, elapsed time and Cancel, in a small window
// at the bottom centre (on screen from the window's first frame, panels open or folded).
void load_window(const UiModel& m, UiActions& a) {
  if (m.loading.empty()) return;
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(ImVec2(vp->WorkPos.x + vp->WorkSize.x * 0.5f, vp->WorkPos.y + vp->WorkSize.y - ui(40)),
                          ImGuiCond_Always, ImVec2(0.5f, 1.0f));
  ImGui::SetNextWindowSize(ImVec2(std::min(ui(460), vp->WorkSize.x - ui(20)), 0), ImGuiCond_Always);
  ImGui::SetNextWindowBgAlpha(0.9f);
  ImGui::Begin("Loading###load", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings |
                   ImGuiWindowFlags_NoFocusOnAppearing);  // its height fits (size 0 above): its text wraps
  colored_wrapped(ImVec4(0.5f, 0.8f, 1.0f, 1), "Loading " + m.loading);
  const LoadView& l = m.load;
  const float fraction = load_fraction(l.bytes_done, l.bytes_total, l.gaussians_done, l.gaussians_total);
  // Which step: the bytes read in full, the Gaussians still being decoded.
  const bool decoding = l.bytes_total > 0 && l.bytes_done >= l.bytes_total && l.gaussians_total > 0 &&
                        l.gaussians_done < l.gaussians_total;
  char elapsed[64];
  std::snprintf(elapsed, sizeof elapsed, "%s%.1f s", decoding ? "decoding, " : "", l.elapsed_s);
  progress_bar(fraction, elapsed, l.elapsed_s);
  std::string detail;
  if (l.bytes_total > 0)
    detail = (l.bytes_done > 0 ? megabytes(l.bytes_done) + " of " : std::string()) + megabytes(l.bytes_total);
  if (l.gaussians_done > 0 || l.gaussians_total > 0) {
    if (!detail.empty()) detail += ", ";
    detail += human_count(double(l.gaussians_done)) +
              (l.gaussians_total > 0 ? " of " + human_count(double(l.gaussians_total)) : std::string()) + " Gaussians";
  }
  if (!detail.empty()) ImGui::TextUnformatted(detail.c_str());
  if (!detail.empty()) ImGui::SameLine();
  if (ImGui::SmallButton("Cancel")) a.cancel_load = true;
  if (!m.scene_path.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyle().Colors[ImGuiCol_TextDisabled]);
    ImGui::TextWrapped("(the current scene stays until the new one is ready)");
    ImGui::PopStyleColor();
  }
  ImGui::End();
}

// One line over the picture: rendered frames per second, time per frame, pairs, backend, and
// whether a frame or a comparison is on its way (the picture shown is then the previous one).
void hud_line(const UiModel& m, float panel_right) {
  const char* backend = m.backend == Backend::cpu ? "CPU" : "CUDA";
  const char* busy = !m.comparing.empty() ? " | comparing..." : m.rendering ? " | rendering..." : "";
  char rate[64], size[32];
  if (m.fps > 0) std::snprintf(rate, sizeof rate, "%.1f FPS | %.0f ms/frame", m.fps, m.last_frame_ms);
  // Still (nothing to redraw): the rate the last frame's time allows, said to be that.
  else if (m.last_frame_ms > 0)
    std::snprintf(rate, sizeof rate, "%.1f FPS at last frame's %.0f ms", 1000.0 / m.last_frame_ms, m.last_frame_ms);
  else std::snprintf(rate, sizeof rate, "no frame timed yet");
  std::snprintf(size, sizeof size, " | %dx%d", m.render_width, m.render_height);
  const std::string pairs = m.stats ? human_count(double(m.stats->kv_pairs)) + " kv pairs" : std::string();
  const std::string full = m.stats ? std::string(rate) + " | " + pairs + " | " + backend + size + busy
                                   : std::string("no frame yet | ") + backend + busy;
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  // Centred, but right of the main panel where the window is narrow (the panel stays
  // readable); the render size goes first, then the pairs, where it would not fit.
  const float room = vp->WorkPos.x + vp->WorkSize.x - std::max(vp->WorkPos.x, panel_right + ui(12)) - ui(10);
  std::string text = full;
  if (m.stats && ImGui::CalcTextSize(text.c_str()).x > room) text = std::string(rate) + " | " + pairs + " | " + backend + busy;
  if (m.stats && ImGui::CalcTextSize(text.c_str()).x > room) text = std::string(rate) + " | " + backend + busy;
  const ImVec2 extent = ImGui::CalcTextSize(text.c_str());
  const float x = std::max(vp->WorkPos.x + (vp->WorkSize.x - extent.x) * 0.5f, panel_right + ui(12));
  const ImVec2 at(x, vp->WorkPos.y + vp->WorkSize.y - extent.y - ui(8));
  ImDrawList* draw = ImGui::GetForegroundDrawList();
  draw->AddRectFilled(ImVec2(at.x - ui(6), at.y - ui(3)), ImVec2(at.x + extent.x + ui(6), at.y + extent.y + ui(3)),
                      IM_COL32(0, 0, 0, 160), ui(3.0f));
  note_drawn_place("status line", at.x, at.y, at.x + extent.x, at.y + extent.y);
  draw->AddText(at, m.rendering ? IM_COL32(255, 220, 120, 255) : IM_COL32(255, 255, 255, 255), text.c_str());
}

// The kernel combo, one row: what the scene file asked for (marked "trained"), and the others
// to compare by eye; where the choice came from is in the tooltip.
void kernel_combo(const UiModel& m, ViewerSettings& s) {
  auto name = [&](const SplatKernel& k) { return k.description() + (k == m.trained ? " (trained)" : ""); };
  ImGui::SetNextItemWidth(ui(262));
  if (ImGui::BeginCombo("Kernel (K)", name(s.options.kernel).c_str())) {
    for (const SplatKernel& k : kTrainerKernels)
      if (ImGui::Selectable(name(k).c_str(), k == s.options.kernel)) s.options.kernel = k;
    ImGui::EndCombo();
  }
  note_widget_place("Kernel (K)");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("the footprint model: classic 3DGS, or the anti-aliased kernel of gsplat (eps 0.3) and "
                      "Mip-Splatting (eps 0.1),\nwhich scales opacity by sqrt(det S / det(S + eps I)).\n"
                      "Trained: %s",
                      m.trained_kernel.c_str());
}

// The streamed cut's level histogram, one bar per level in the level overlay's colour: the
// overlay's legend and the Gaussians drawn at each level.
void level_histogram(const std::vector<std::uint64_t>& drawn) {
  std::uint64_t most = 1;
  for (std::uint64_t n : drawn) most = std::max(most, n);
  const float h = ImGui::GetTextLineHeight(), width = ui(150);
  ImDrawList* draw = ImGui::GetWindowDrawList();
  for (std::size_t level = 0; level < drawn.size(); ++level) {
    const std::array<float, 3> c = lod_level_colour(static_cast<int>(level));
    const ImU32 colour = ImGui::ColorConvertFloat4ToU32(ImVec4(c[0], c[1], c[2], 1.0f));
    const ImVec2 at = ImGui::GetCursorScreenPos();
    const float filled = width * static_cast<float>(static_cast<double>(drawn[level]) / static_cast<double>(most));
    draw->AddRectFilled(at, ImVec2(at.x + width, at.y + h), IM_COL32(60, 60, 60, 255));
    draw->AddRectFilled(at, ImVec2(at.x + filled, at.y + h), colour);
    ImGui::Dummy(ImVec2(width, h));
    ImGui::SameLine();
    ImGui::Text("level %zu: %s", level, human_count(double(drawn[level])).c_str());
  }
}

// The bytes the stream read per second over the last half minute.
void read_rate_graph(const std::vector<float>& rates) {
  float top = 1.0f;
  for (float r : rates) top = std::max(top, r);
  const std::string latest = "read " + format_bytes(static_cast<std::uint64_t>(rates.empty() ? 0.0f : rates.back())) + "/s";
  ImGui::PlotLines("##read rate", rates.data(), static_cast<int>(rates.size()), 0, latest.c_str(), 0.0f, top * 1.1f,
                   ImVec2(ui(260), ui(40)));
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("chunk bytes read from the disk per second, last 30 s (top: %s/s)",
                                                format_bytes(static_cast<std::uint64_t>(top)).c_str());
}

void scene_panel(const UiModel& m, ViewerSettings& s, UiActions& a, std::string& path_buffer) {
  if (!ImGui::CollapsingHeader("Scene", ImGuiTreeNodeFlags_DefaultOpen)) return;
  if (m.scene_path.empty()) {
    ImGui::TextDisabled(m.loading.empty() ? "no scene loaded" : "no scene yet: loading (below)");
  } else {
    ImGui::TextWrapped("%s", m.scene_path.c_str());
    ImGui::Text("%s Gaussians, SH degree %d, %d cameras", human_count(double(m.gaussians)).c_str(), m.sh_degree,
                m.camera_count);
    kernel_combo(m, s);
  }
  if (m.lod_gaussians && !m.lod_gaussians->empty()) {
    // A SOG LOD set: any level, loaded in the background like a new file (the frame time is in the HUD).
    auto level_name = [&](int level) {
      return "level " + std::to_string(level) + ": " + human_count(double((*m.lod_gaussians)[level])) + " Gaussians";
    };
    ImGui::SetNextItemWidth(ui(260));
    // While streamed, every cell has its own level; choosing one loads that level whole.
    const std::string shown = m.stream_summary.empty() ? level_name(m.lod_level) : "streamed by view";
    if (ImGui::BeginCombo("LOD", shown.c_str())) {
      for (int level = 0; level < static_cast<int>(m.lod_gaussians->size()); ++level)
        if (ImGui::Selectable(level_name(level).c_str(), level == m.lod_level && m.stream_summary.empty()) &&
            (level != m.lod_level || !m.stream_summary.empty()))
          a.lod_level = level;
      ImGui::EndCombo();
    }
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("level 0 is the finest; a coarser level has fewer Gaussians");
  }
  if (!m.stream_summary.empty()) {
    // Streamed by view: each cell at the level the view needs; chunks arrive in the background.
    ImGui::TextWrapped("streamed: %s", m.stream_summary.c_str());
    ImGui::SetNextItemWidth(ui(200));
    ImGui::SliderFloat("max error (px)", &s.stream_max_error_px, 0.0f, 16.0f, "%.1f");
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("a cell is drawn finer while its Gaussians' spacing, projected, is larger than this");
    ImGui::SetNextItemWidth(ui(200));
    ImGui::SliderFloat("budget (M)", &s.stream_budget_millions, 0.0f, 100.0f, s.stream_budget_millions > 0 ? "%.2f M" : "caps only");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Gaussians drawn at most, in millions (0: what the memory caps allow)");
    ImGui::Checkbox("level colours", &s.lod_overlay);
    note_widget_place("level colours");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("each Gaussian in the colour of the level it is drawn at (the legend below)");
    level_histogram(m.stream_levels);
    if (m.stream_read_rates) read_rate_graph(*m.stream_read_rates);
  }
  if (!m.scene_note.empty()) {
    colored_wrapped(ImVec4(0.9f, 0.8f, 0.4f, 1), m.scene_note);
  }
  ImGui::SetNextItemWidth(ui(-170));
  const bool enter = ImGui::InputTextWithHint("##open", "scene file or folder", &path_buffer,
                                              ImGuiInputTextFlags_EnterReturnsTrue);
  // Enter ends the edit, but the typing goes on in the box (a mistyped path is corrected
  // there): letters typed next must not reach the single-key shortcuts.
  if (enter) {
    ImGui::SetKeyboardFocusHere(-1);
    a.path_entered = true;
  }
  note_widget_place("path field");
  ImGui::SameLine();
  if ((ImGui::Button("Open") || enter) && !path_buffer.empty()) a.open_path = path_buffer;
  ImGui::SameLine();
  ImGui::BeginDisabled(m.dialog_open);
  if (ImGui::Button("Browse...")) a.open_dialog = true;
  ImGui::EndDisabled();
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) ImGui::SetTooltip("the desktop's file dialog (Ctrl+O)");
  // The recent scenes behind an arrow on the same row: the panel's layout does not move.
  ImGui::SameLine();
  const bool any_recent = m.recent && !m.recent->empty();
  ImGui::BeginDisabled(!any_recent);
  if (ImGui::BeginCombo("##recent", nullptr, ImGuiComboFlags_NoPreview | ImGuiComboFlags_PopupAlignLeft)) {
    ImGui::TextDisabled("recent scenes");
    if (any_recent)
      for (const std::string& r : *m.recent)
        if (ImGui::Selectable(r.c_str())) a.open_path = r;
    ImGui::EndCombo();
  }
  ImGui::EndDisabled();
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
    ImGui::SetTooltip(any_recent ? "recently opened scenes" : "no recent scenes yet");
  // On a line of its own: beside the Browse button it was cut off at the panel's edge.
  if (m.dialog_open) ImGui::TextDisabled("waiting for %s", m.dialog_tool.empty() ? "the file browser" : m.dialog_tool.c_str());
  if (!m.load_error.empty()) {
    colored_wrapped(ImVec4(1.0f, 0.45f, 0.4f, 1), m.load_error);
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
    note_widget_place("s per camera");
    ImGui::TextUnformatted(m.view_description.c_str());  // one line: the sliders below stay put
  } else if (!m.scene_path.empty()) {
    ImGui::TextDisabled("no cameras.json: free navigation");
  }
  ImGui::SliderFloat("FOV (deg)", &s.fov_x_degrees, kFovRange.min, kFovRange.max, "%.1f", kClamp);
  note_widget_place("FOV (deg)");
  ImGui::SliderFloat("Speed", &s.move_speed, kMoveSpeedRange.min, kMoveSpeedRange.max, "%.3g extents/s",
                     kClamp | ImGuiSliderFlags_Logarithmic);
  ImGui::SliderFloat("Render scale", &s.render_scale, kRenderScaleRange.min, kRenderScaleRange.max, "%.2f", kClamp);
  note_widget_place("Render scale");
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
  greyed_checkbox("Frustums", &s.show_frustums, m.camera_count > 0);
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
    ImGui::SetTooltip(m.camera_count ? "the training cameras; click one to jump to it" : "the scene has no cameras");
}

// One optimisation switch: a checkbox greyed out where the backend does not honour it, and a
// tooltip saying what it removes, where the paper has it, its CLI flag and why it is grey.
void switch_checkbox(const RenderSwitch& sw, RenderOptions& o, Backend backend) {
  const bool honoured = sw.honoured_by(backend);
  greyed_checkbox(sw.ui_name, &(o.*(sw.member)), honoured && !o.is_baseline());
  note_widget_place(sw.ui_name);
  if (!ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) return;
  std::string tip = std::string(sw.help) + "\nFlashGS paper: " + sw.paper + "\nCLI: --no-" + sw.cli_name;
  if (!honoured) tip += std::string("\nGreyed out: the ") + backend_name(backend) + " backend ignores it (" +
                        sw.why_ignored + ")";
  else if (o.is_baseline()) tip += "\nGreyed out: the baseline uses none of the optimisations";
  ImGui::SetTooltip("%s", tip.c_str());
}

void render_panel(const UiModel& m, ViewerSettings& s) {
  RenderOptions& o = s.options;
  int algo = o.is_baseline() ? 0 : 1;
  ImGui::RadioButton("Baseline (3DGS)", &algo, 0);
  note_widget_place("Baseline (3DGS)");
  ImGui::SameLine();
  ImGui::RadioButton("Flash", &algo, 1);
  note_widget_place("Flash");
  ImGui::SameLine();
  ImGui::TextDisabled("(B)");
  switch_algorithm(o, algo == 0 ? Algorithm::baseline : Algorithm::flash);
  // Two columns: the switches that change the Gaussian-tile pairs (geometry) and those that
  // only change how fast the kernels make and blend them; under the shorter geometry column,
  // the precision options, so that the panels' last buttons stay on a 720-px window.
  if (ImGui::BeginTable("opts", 2, ImGuiTableFlags_SizingStretchSame)) {
    for (const bool geometry : {true, false}) {
      ImGui::TableNextColumn();
      ImGui::TextDisabled(geometry ? "geometry" : "GPU kernels");
      for (const RenderSwitch& sw : kRenderSwitches)
        if (sw.changes_pairs == geometry) switch_checkbox(sw, o, m.backend);
      if (!geometry) continue;
      ImGui::TextDisabled("precision");
      ImGui::SetNextItemWidth(ui(40));
      ImGui::SliderInt("SH degree cap", &o.sh_degree_cap, 0, kMaxShDegree, "%d", kClamp);
      ImGui::Checkbox("fp16 SH", &o.fp16_sh);
      if (ImGui::IsItemHovered())
        ImGui::SetTooltip("the SH coefficients as half values: half the GPU bytes of the SH bands, not exact");
      // On the SH box's line, so that the panel is no taller than the GPU column beside it.
      ImGui::SameLine();
      ImGui::Checkbox("shape##fp16 shape", &o.fp16_shape);
      if (ImGui::IsItemHovered())
        ImGui::SetTooltip("fp16 shape: rotation, scale and opacity as half values: 16 GPU bytes instead of 32, not exact");
      // The half blend exists only as a CUDA kernel, and only for the exp2 loop.
      const bool half_blend_runs = m.backend == Backend::cuda && !o.is_baseline() && o.exp2_alpha;
      greyed_checkbox("fp16 blend", &o.fp16_blend, half_blend_runs);
      if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
        ImGui::SetTooltip("%s", half_blend_runs ? "the blend in half arithmetic, two pixels per instruction: faster, not exact"
                                                : "the blend in half arithmetic: a CUDA kernel of the flash path with exp2 "
                                                  "alpha (greyed out: not in effect here)");
    }
    ImGui::EndTable();
  }
  float inv_tau = 1.0f / o.tau;
  char tau_label[64];
  std::snprintf(tau_label, sizeof tau_label, "1/tau (tau %.5f)###tau", o.tau);
  if (ImGui::SliderFloat(tau_label, &inv_tau, 1.0f / kTauRange.max, 1.0f / kTauRange.min, "%.0f",
                         kClamp | ImGuiSliderFlags_Logarithmic))
    o.tau = 1.0f / inv_tau;
  ImGui::ColorEdit3("Background", o.background, ImGuiColorEditFlags_NoInputs);
  ImGui::SameLine();
  ImGui::Checkbox("Every frame", &s.continuous);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("re-render every frame (off: only when the view or an option changes)");
  ImGui::SameLine();
  ImGui::Checkbox("VSync", &s.vsync);
}

// "114.2 (110.1-119.0)": a median and its range.
std::string spread_cell(const Spread& s) {
  char text[64];
  std::snprintf(text, sizeof text, "%.1f (%.1f-%.1f)", s.median, s.min, s.max);
  return text;
}

void compare_panel(const UiModel& m, ViewerSettings& s, UiActions& a) {
  // The two sides: any two of the configurations compare_mode.h lists that the backend draws
  // differently (a switch it ignores renders flash itself).
  auto side = [&](const char* label, int* choice) {
    ImGui::SetNextItemWidth(ui(150));
    if (ImGui::BeginCombo(label, compare_choice_title(*choice).c_str())) {
      for (int c = 0; c < compare_choice_count(); ++c)
        if (compare_choice_offered(c, m.backend) && ImGui::Selectable(compare_choice_title(c).c_str(), c == *choice))
          *choice = c;
      ImGui::EndCombo();
    }
    note_widget_place(label);
  };
  side("left", &s.compare_left);
  side("right", &s.compare_right);
  ImGui::BeginDisabled(!m.compare_problem.empty() || !m.comparing.empty());  // one comparison at a time
  if (ImGui::Button("Compare this view (C)")) a.compare = true;
  note_widget_place("Compare this view (C)");
  ImGui::EndDisabled();
  ImGui::SameLine();
  int view = static_cast<int>(s.compare_view);
  const char* views[] = {"numbers only", "split view", "difference"};
  ImGui::SetNextItemWidth(ui(120));
  ImGui::Combo("##view", &view, views, 3);
  s.compare_view = static_cast<CompareView>(view);
  if (!m.comparing.empty()) {
    colored_wrapped(ImVec4(1.0f, 0.86f, 0.47f, 1), "comparing " + m.comparing);
    char overlay[64];
    std::snprintf(overlay, sizeof overlay, "render %d of %d, %.1f s", std::min(m.compare_renders_done + 1, m.compare_renders_total),
                  m.compare_renders_total, m.compare_elapsed_s);
    progress_bar(m.compare_renders_total > 0 ? float(m.compare_renders_done) / float(m.compare_renders_total) : -1.0f,
                 overlay, m.compare_elapsed_s);
    return;
  }
  if (!m.compare_problem.empty()) {
    colored_wrapped(ImVec4(0.9f, 0.8f, 0.4f, 1), m.compare_problem);
    return;
  }
  const CompareResult* c = m.compare;
  if (!c || (!c->valid && c->error.empty())) return;
  if (!c->error.empty()) {
    colored_wrapped(ImVec4(1, 0.45f, 0.4f, 1), c->error);
    return;
  }
  if (c->stale) ImGui::TextColored(ImVec4(0.9f, 0.8f, 0.4f, 1), "(view changed: C again)");
  ImGui::TextWrapped("%s (right) vs %s (left) at %dx%d", c->right_label.c_str(), c->left_label.c_str(), c->width, c->height);
  if (std::isinf(c->difference.psnr_db)) ImGui::Text("PSNR: identical   max abs: 0");
  else ImGui::Text("PSNR %.2f dB   max abs %.5f (%.2f/255)", c->difference.psnr_db, c->difference.max_abs,
                   c->difference.max_abs * 255.0);
  ImGui::Text("pixels off by > 1/255: %.4f%%", 100.0 * c->difference.fraction_over_1_255);
  if (s.compare_view == CompareView::difference) ImGui::Text("difference image: |error| x %.0f", m.difference_factor);
  const bool noise = within_noise(c->speed_up);
  ImGui::PushStyleColor(ImGuiCol_Text, noise ? ImVec4(0.9f, 0.8f, 0.4f, 1) : ImGui::GetStyle().Colors[ImGuiCol_Text]);
  ImGui::TextWrapped("%s", speed_up_text(*c).c_str());
  ImGui::PopStyleColor();
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("median of the rounds' left time / right time, and its range; each side rendered once untimed "
                      "first, then both sides each round, in alternating order.\nWithin noise: some rounds found "
                      "the other side faster.");
  ImGui::Text("pair reduction %.1f%%", 100.0 * c->pair_reduction());
  if (ImGui::BeginTable("cmp", 3, ImGuiTableFlags_BordersInnerH)) {
    ImGui::TableSetupColumn("");
    ImGui::TableSetupColumn("left");
    ImGui::TableSetupColumn("right");
    ImGui::TableHeadersRow();
    ImGui::TableNextRow();
    ImGui::TableNextColumn(); ImGui::Text("frame ms");
    ImGui::TableNextColumn(); ImGui::TextUnformatted(spread_cell(c->left_ms).c_str());
    ImGui::TableNextColumn(); ImGui::TextUnformatted(spread_cell(c->right_ms).c_str());
    ImGui::TableNextRow();
    ImGui::TableNextColumn(); ImGui::Text("wall ms");
    ImGui::TableNextColumn(); ImGui::TextUnformatted(spread_cell(c->left_wall_ms).c_str());
    ImGui::TableNextColumn(); ImGui::TextUnformatted(spread_cell(c->right_wall_ms).c_str());
    ImGui::TableNextRow();
    ImGui::TableNextColumn(); ImGui::Text("kv pairs");
    ImGui::TableNextColumn(); ImGui::Text("%s", human_count(double(c->left_kv)).c_str());
    ImGui::TableNextColumn(); ImGui::Text("%s", human_count(double(c->right_kv)).c_str());
    ImGui::EndTable();
  }
}

// The keyframed camera path: keys from the view (I), their times, easing, preview, the file,
// and the render of its frames (size, fps, duration, folder; progress and Cancel).
void keyframe_panel(const UiModel& m, UiActions& a, PathEditor& keys, PathFields& f) {
  KeyframePath& p = keys.path();
  if (ImGui::Button("Add view (I)")) a.add_key = true;
  note_widget_place("Add view (I)");
  ImGui::SameLine();
  ImGui::BeginDisabled(keys.selected() < 0);
  if (ImGui::Button("Replace")) a.replace_key = true;
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) ImGui::SetTooltip("the selected key takes the view");
  ImGui::SameLine();
  if (ImGui::Button("Delete")) a.delete_key = true;
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(p.keys.size() < 2);
  if (ImGui::Button(keys.previewing() ? "Stop" : "Preview")) a.toggle_preview = true;
  ImGui::EndDisabled();
  if (!p.keys.empty()) {
    ImGui::BeginChild("keys", ImVec2(0, ImGui::GetTextLineHeightWithSpacing() * std::min<float>(4.5f, p.keys.size() + 0.5f)),
                      true);
    for (std::size_t i = 0; i < p.keys.size(); ++i) {
      char row[96];
      std::snprintf(row, sizeof row, "key %zu   %.2f s   FOV %.1f", i, p.keys[i].time_s, p.keys[i].fov_x_degrees);
      if (ImGui::Selectable(row, int(i) == keys.selected())) a.select_key = int(i);
    }
    ImGui::EndChild();
  }
  if (keys.selected() >= 0) {
    double t = p.keys[std::size_t(keys.selected())].time_s;
    ImGui::SetNextItemWidth(ui(90));
    if (ImGui::InputDouble("key time (s)", &t, 0.1, 1.0, "%.2f")) keys.set_time(keys.selected(), t);
    ImGui::SameLine();
  }
  int easing = p.easing == PathEasing::linear ? 0 : 1;
  const char* easings[] = {"linear", "ease in/out"};
  ImGui::SetNextItemWidth(ui(100));
  if (ImGui::Combo("easing", &easing, easings, 2)) p.easing = easing == 0 ? PathEasing::linear : PathEasing::ease_in_out;
  ImGui::SetNextItemWidth(ui(-110));
  ImGui::InputTextWithHint("##keysfile", "path file (.json)", &f.file);
  ImGui::SameLine();
  ImGui::BeginDisabled(p.keys.empty() || f.file.empty());
  if (ImGui::Button("Save##keys")) a.save_keys = true;
  note_widget_place("Save path");
  ImGui::EndDisabled();
  ImGui::SameLine();
  ImGui::BeginDisabled(f.file.empty());
  if (ImGui::Button("Load##keys")) a.load_keys = true;
  ImGui::EndDisabled();
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
    ImGui::SetTooltip("this viewer's path files, or nerfstudio's camera_path.json");
  if (p.keys.size() < 2) return;
  // The render: its size is its own, not the window's.
  int size[2] = {p.width, p.height};
  ImGui::SetNextItemWidth(ui(110));
  if (ImGui::InputInt2("size", size)) {
    p.width = std::clamp(size[0], 16, kMaxPathSide);
    p.height = std::clamp(size[1], 16, kMaxPathSide);
  }
  ImGui::SameLine();
  ImGui::SetNextItemWidth(ui(40));
  if (ImGui::InputInt("fps", &p.fps, 0)) p.fps = std::clamp(p.fps, 1, kMaxPathFps);
  ImGui::SameLine();
  double duration = p.duration_s();
  ImGui::SetNextItemWidth(ui(60));
  if (ImGui::InputDouble("s", &duration, 0, 0, "%.1f") && duration > 0.05) keys.set_duration(duration);
  if (m.export_total > 0) {
    ImGui::ProgressBar(float(m.export_done) / float(m.export_total), ImVec2(ui(-70), 0));
    ImGui::SameLine();
    if (ImGui::Button("Cancel##keys")) a.cancel_export = true;
    return;
  }
  ImGui::SetNextItemWidth(ui(-110));
  ImGui::InputTextWithHint("##keysfolder", "folder for the frames", &f.folder);
  ImGui::SameLine();
  ImGui::BeginDisabled(f.folder.empty());
  char label[48];
  std::snprintf(label, sizeof label, "Render %d", p.frame_count());
  if (ImGui::Button(label)) a.render_keys_folder = f.folder;
  note_widget_place("Render path");
  ImGui::EndDisabled();
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
    ImGui::SetTooltip("frame_00000.png, ... at this size and fps; path.mp4 too when ffmpeg is on PATH");
}

void overlay_panel(const UiModel& m, ViewerSettings& s, UiActions& a, std::string& export_folder) {
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
  ImGui::SetNextItemWidth(ui(150));
  if (ImGui::BeginCombo("View (V)", frame_view_label(s.view))) {
    for (FrameView v : kFrameViews)
      if (ImGui::Selectable(frame_view_label(v), v == s.view)) s.view = v;
    ImGui::EndCombo();
  }
  note_widget_place("View");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("Depth: the blended depth sum(w z) / sum(w), w = alpha T, per pixel; Blended count: the "
                      "Gaussians each pixel blended before it stopped.\nBoth from the per-pixel blend that makes the "
                      "colour (on %s: %s), so slower than the colour frame.",
                      m.backend == Backend::cpu ? "the CPU" : "CUDA",
                      m.backend == Backend::cpu ? "its scalar kernel"
                                                : "the per-pixel 3DGS kernel, also when flash is chosen");
  ImGui::SameLine();
  ImGui::Checkbox("Gaussian centres", &s.show_centres);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("each Gaussian's centre as a dot in its base colour (at most %d; every k-th beyond)",
                      int(kMaxCentreMarks));
  ImGui::SetNextItemWidth(ui(-90));
  ImGui::InputTextWithHint("##shotdir", "screenshot folder", &s.screenshot_folder);
  ImGui::SameLine();
  if (ImGui::Button("Save (F12)")) a.screenshot = true;
  if (m.export_total > 0) {
    ImGui::ProgressBar(float(m.export_done) / float(m.export_total), ImVec2(ui(-70), 0));
    ImGui::SameLine();
    if (ImGui::Button("Cancel##export")) a.cancel_export = true;
  } else if (m.camera_count > 0) {
    ImGui::SetNextItemWidth(ui(-90));
    ImGui::InputTextWithHint("##export", "folder for the path's frames", &export_folder);
    note_widget_place("export folder");
    ImGui::SameLine();
    if (ImGui::Button("Export path") && !export_folder.empty()) a.export_folder = export_folder;
    note_widget_place("Export path");
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("one loop of the camera path as frame_00000.png, ...; also path.mp4 when ffmpeg is on PATH");
  }
}

void stats_window(const UiModel& m) {
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  // Starts top right; it can be moved (and the place is kept with the layout).
  ImGui::SetNextWindowPos(ImVec2(vp->WorkPos.x + vp->WorkSize.x - ui(10), vp->WorkPos.y + ui(10)),
                          ImGuiCond_FirstUseEver, ImVec2(1, 0));
  // In a small window the panels would cover the picture: statistics start folded there.
  ImGui::SetNextWindowCollapsed(vp->WorkSize.x < ui(1000), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowBgAlpha(0.75f);
  // The title keeps the frame rate in view when the window is folded.
  char title[256];
  if (m.fps > 0) std::snprintf(title, sizeof title, "%.1f FPS | %s###Statistics", m.fps, m.frame_path.c_str());
  else if (m.last_frame_ms > 0)  // still: the last frame's time (the title's width is fixed)
    std::snprintf(title, sizeof title, "%.0f ms/frame | %s###Statistics", m.last_frame_ms, m.frame_path.c_str());
  else std::snprintf(title, sizeof title, "no frame yet | %s###Statistics", m.frame_path.c_str());
  // A fixed width: the anchor above places its right edge from the first frame on.
  ImGui::SetNextWindowSizeConstraints(ImVec2(ui(330), 0), ImVec2(ui(330), vp->WorkSize.y));
  ImGui::Begin(title, nullptr, ImGuiWindowFlags_AlwaysAutoResize);
  keep_inside_viewport("Statistics corner");
  colored_wrapped(ImVec4(0.5f, 0.9f, 0.6f, 1), m.frame_path);
  if (!m.frame_path_note.empty()) ImGui::TextWrapped("%s", m.frame_path_note.c_str());
  ImGui::Text("rendered: %.1f FPS   render %dx%d", m.fps, m.render_width, m.render_height);
  if (const FrameStats* st = m.stats) {
    ImGui::Separator();
    ImGui::TextDisabled("last frame");
    // Two lines: one did not fit the window's fixed width once frames took 10 ms or more.
    ImGui::Text("%.1f ms   kv pairs %s", m.last_frame_ms, human_count(double(st->kv_pairs)).c_str());
    ImGui::Text("visible %s of %s Gaussians", human_count(double(st->visible)).c_str(),
                human_count(double(st->gaussians)).c_str());
    ImGui::Text("culled: near %s  off-screen %s", human_count(double(st->culled_near)).c_str(),
                human_count(double(st->culled_offscreen)).c_str());
    ImGui::Text("        low-opacity %s  degenerate %s", human_count(double(st->culled_low_opacity)).c_str(),
                human_count(double(st->culled_degenerate)).c_str());
    if (st->device_peak_bytes > 0)
      ImGui::Text("device memory %.1f MB (peak %.1f MB)", st->device_memory_bytes / 1e6, st->device_peak_bytes / 1e6);
    ImGui::Text("project %.1f  emit %.1f  sort %.1f ms", st->times.project_ms, st->times.emit_ms, st->times.sort_ms);
    ImGui::Text("ranges %.1f  blend %.1f ms%s", st->times.ranges_ms, st->times.blend_ms,
                st->times.sort_in_blend ? " (+ bin sort)" : "");
    if (st->times.sort_in_blend && ImGui::IsItemHovered()) ImGui::SetTooltip("%s", blend_time_note(st->times));
  }
  if (const StatsHistory* h = m.history) {
    if (ImGui::CollapsingHeader("mean and max over recent frames")) {
      const StatsHistory::Series shown[] = {StatsHistory::kFrame, StatsHistory::kRender, StatsHistory::kProject,
                                            StatsHistory::kEmit, StatsHistory::kSort, StatsHistory::kBlend};
      for (StatsHistory::Series s : shown) {
        int count = 0, offset = 0;
        const float* values = h->series(s, &count, &offset);
        char overlay[64];
        std::snprintf(overlay, sizeof overlay, "%s mean %.2f ms (max %.2f)", StatsHistory::name(s), h->mean(s), h->max(s));
        ImGui::PlotLines("##h", values, count, offset, overlay, 0.0f, float(h->max(s) * 1.1 + 1e-3),
                         ImVec2(ui(260), ui(s == StatsHistory::kFrame ? 40 : 24)));
      }
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
  // The caption starts over the bar's left end, or further left where it would pass the
  // window's right edge (the locked caption is longer than the bar).
  const std::string caption = legend_caption(m.tile_size, s.heatmap_log, s.heatmap_lock_max);
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  const float caption_x = std::max(vp->WorkPos.x + ui(6), std::min(r[0], vp->WorkPos.x + vp->WorkSize.x - ui(6) -
                                                                     ImGui::CalcTextSize(caption.c_str()).x));
  draw->AddRectFilled(ImVec2(caption_x - ui(6), r[1] - line - ui(6)), ImVec2(r[2] + ui(6), r[1]), backing, ui(3.0f));
  draw->AddRectFilled(ImVec2(r[0] - ui(16), r[3]), ImVec2(r[2] + ui(16), r[3] + line + ui(6)), backing, ui(3.0f));
  draw->AddText(ImVec2(caption_x, r[1] - line - ui(3)), white, caption.c_str());
  note_drawn_place("legend caption", caption_x, r[1] - line - ui(3),
                   caption_x + ImGui::CalcTextSize(caption.c_str()).x, r[1] - ui(3));
  for (const LegendTick& t : legend_ticks(m.heatmap_max, s.heatmap_log)) {
    const float x = r[0] + t.position * (r[2] - r[0]);
    draw->AddLine(ImVec2(x, r[3]), ImVec2(x, r[3] + ui(4)), white, ui(1.0f));
    const float w = ImGui::CalcTextSize(t.label.c_str()).x;
    draw->AddText(ImVec2(x - 0.5f * w, r[3] + ui(4)), white, t.label.c_str());
  }
}

// The debug view's legend, bar included (drawn here: no shader draws it), the width of the
// heat map's and above it (the two may be on together).
void debug_legend(const UiModel& m, const ViewerSettings& s) {
  if (m.debug_shown == FrameView::colour) return;
  ImDrawList* draw = ImGui::GetForegroundDrawList();
  const float* heat = m.legend_rect_points;
  const float lift = s.heatmap ? ui(60) : 0.0f;
  const float r[4] = {heat[0], heat[1] - lift, heat[2], heat[3] - lift};
  const ImU32 white = IM_COL32(255, 255, 255, 255), backing = IM_COL32(0, 0, 0, 160);
  const float line = ImGui::GetTextLineHeight();
  const std::string caption = debug_legend_caption(m.debug_shown);
  draw->AddRectFilled(ImVec2(r[0] - ui(16), r[1] - line - ui(6)), ImVec2(r[2] + ui(16), r[3] + line + ui(6)), backing,
                      ui(3.0f));
  draw->AddText(ImVec2(r[0], r[1] - line - ui(3)), white, caption.c_str());
  // The ramp as one gradient between each pair of its stops.
  auto colour = [](const std::array<float, 3>& c) { return ImGui::ColorConvertFloat4ToU32(ImVec4(c[0], c[1], c[2], 1)); };
  for (int i = 0; i + 1 < kRampStops; ++i) {
    const float x0 = r[0] + (r[2] - r[0]) * float(i) / (kRampStops - 1);
    const float x1 = r[0] + (r[2] - r[0]) * float(i + 1) / (kRampStops - 1);
    const ImU32 a = colour(kHeatRamp[i]), b = colour(kHeatRamp[i + 1]);
    draw->AddRectFilledMultiColor(ImVec2(x0, r[1]), ImVec2(x1, r[3]), a, b, b, a);
  }
  for (const LegendTick& t : debug_legend_ticks(m.debug_shown, m.debug_scale)) {
    const float x = r[0] + t.position * (r[2] - r[0]);
    draw->AddLine(ImVec2(x, r[3]), ImVec2(x, r[3] + ui(4)), white, ui(1.0f));
    const float w = ImGui::CalcTextSize(t.label.c_str()).x;
    draw->AddText(ImVec2(x - 0.5f * w, r[3] + ui(4)), white, t.label.c_str());
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
    // Centred above the heads-up line: at the left edge it was drawn over the panel's text.
    label(vp->WorkPos.x + 0.5f * (vp->WorkSize.x - ImGui::CalcTextSize(text).x), text);
    return;
  }
  const float at = vp->WorkPos.x + m.divider * vp->WorkSize.x;
  label(at - ui(12) - ImGui::CalcTextSize(c->left_label.c_str()).x, c->left_label);
  label(at + ui(12), c->right_label);
}

// A tab of the sections' bar; its place is logged as "tab NAME" (--log-input).
bool section_tab(const char* name, bool select) {
  const bool open = ImGui::BeginTabItem(name, nullptr, select ? ImGuiTabItemFlags_SetSelected : 0);
  note_widget_place((std::string("tab ") + name).c_str());
  return open;
}

// Below Scene and View, one section at a time: the panel stays short enough at 1280x800 that
// every action is on screen without scrolling (stacked, the Compare results and the export
// were below the fold).
void section_tabs(const UiModel& m, ViewerSettings& s, UiActions& a, std::string& export_folder, PathEditor& keys,
                  PathFields& key_fields) {
  // A comparison started with C (from any tab), or its result arriving, brings its tab forward once.
  static bool was_comparing = false, had_result = false;
  const bool comparing = !m.comparing.empty(), result = m.compare && (m.compare->valid || !m.compare->error.empty());
  const bool show_compare = (comparing && !was_comparing) || (result && !had_result);
  was_comparing = comparing;
  had_result = result;
  if (!ImGui::BeginTabBar("sections")) return;
  if (section_tab("Rendering", false)) {
    render_panel(m, s);
    ImGui::EndTabItem();
  }
  if (section_tab("Compare", show_compare)) {
    compare_panel(m, s, a);
    ImGui::EndTabItem();
  }
  if (section_tab("Camera path", false)) {
    keyframe_panel(m, a, keys, key_fields);
    ImGui::EndTabItem();
  }
  if (section_tab("Overlay & output", false)) {
    overlay_panel(m, s, a, export_folder);
    ImGui::EndTabItem();
  }
  ImGui::EndTabBar();
}

}  // namespace

void draw_panels(const UiModel& m, ViewerSettings& s, UiActions& a, std::string& path_buffer, std::string& export_folder,
                 PathEditor& keys, PathFields& key_fields) {
  g_ui = m.ui_scale;
  ImGui::SetNextWindowPos(ImVec2(ui(10), ui(10)), ImGuiCond_FirstUseEver);
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowSizeConstraints(ImVec2(ui(300), ui(100)), ImVec2(ui(600), std::max(ui(120), vp->WorkSize.y - ui(20))));
  ImGui::SetNextWindowSize(ImVec2(ui(380), 0), ImGuiCond_FirstUseEver);
  // A new scene adds rows (its counts, the camera path, the export row): the panel's height
  // fits its content again, up to the window's (a height of 0 asks ImGui for that fit), so
  // that nothing below ends up cut off under the panel's first, scene-less height.
  static std::string fitted_for;
  static float panel_width = 0;
  const std::string scene_key = m.scene_path + "|" + std::to_string(m.gaussians) + "|" + std::to_string(m.camera_count);
  if (scene_key != fitted_for && panel_width > 0) ImGui::SetNextWindowSize(ImVec2(panel_width, 0), ImGuiCond_Always);
  fitted_for = scene_key;
  ImGui::SetNextWindowBgAlpha(0.85f);
  // The scrollbar's room is always kept: a scrollbar that came and went with the open tab's
  // height would rewrap the scene path and move every widget under the pointer.
  ImGui::Begin("flashgs-viewer", nullptr, ImGuiWindowFlags_AlwaysVerticalScrollbar);
  keep_inside_viewport("panel corner");
  panel_width = ImGui::GetWindowSize().x;
  const float panel_right = ImGui::GetWindowPos().x + ImGui::GetWindowSize().x;
  ImGui::PushItemWidth(ImGui::GetWindowWidth() * 0.5f);  // leaves room for the labels
  scene_panel(m, s, a, path_buffer);
  view_panel(m, s, a);
  section_tabs(m, s, a, export_folder, keys, key_fields);
  // The last notice (a screenshot saved, a key added, a refusal) under the tabs, whichever is open.
  if (!m.status.empty()) {
    ImGui::Separator();
    ImGui::TextWrapped("%s", m.status.c_str());
  }
  if (ImGui::Button("Keys and mouse (F1)")) s.show_help = !s.show_help;
  ImGui::SameLine();
  ImGui::TextDisabled("Tab hides the panels");
  ImGui::PopItemWidth();
  ImGui::End();
  stats_window(m);
  load_window(m, a);
  g_panel_right = panel_right;
}

void draw_legend_labels(const UiModel& m, const ViewerSettings& s) {
  g_ui = m.ui_scale;
  if (s.heatmap && !m.compare_shown) legend_labels(m, s);
  if (!m.compare_shown) debug_legend(m, s);
}

void draw_overlays(const UiModel& m, ViewerSettings& s) {
  g_ui = m.ui_scale;
  if (s.heatmap && !m.compare_shown) legend_labels(m, s);
  if (!m.compare_shown) debug_legend(m, s);
  compare_labels(m, s);
  draw_help_window(&s.show_help, m.ui_scale);
  if (!s.show_ui) draw_hidden_panels_hint(m.ui_scale);
  // With the panels hidden (Tab) too: the rate and the render size are what one hides them to watch.
  hud_line(m, s.show_ui ? g_panel_right : ImGui::GetMainViewport()->WorkPos.x - ui(12));
}

}  // namespace flashgs::viewer
