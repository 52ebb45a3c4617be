// Where the widgets that tests click are on screen, logged under --log-input.
#include "widget_places_ui.h"

#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include <imgui.h>

namespace flashgs::viewer {
namespace {
bool g_logging = false;
std::map<std::string, ImVec2>& last_places() {
  static std::map<std::string, ImVec2> places;
  return places;
}
}  // namespace

void set_widget_place_logging(bool on) { g_logging = on; }

void note_widget_place(const char* name) {
  // Only where it can be clicked: inside its window's visible part (not scrolled away).
  if (!g_logging || !ImGui::IsItemVisible()) return;
  const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
  note_drawn_place(name, lo.x, lo.y, hi.x, hi.y);
}

void note_drawn_place(const char* name, float x0, float y0, float x1, float y1) {
  if (!g_logging) return;
  // ImGui's points are the window's coordinates: the ones the cursor and XTEST use.
  const ImVec2 centre(std::round((x0 + x1) * 0.5f), std::round((y0 + y1) * 0.5f));
  auto [at, inserted] = last_places().try_emplace(name, centre);
  if (!inserted && at->second.x == centre.x && at->second.y == centre.y) return;
  at->second = centre;
  std::fprintf(stderr, "flashgs-viewer: widget \"%s\" at %.0f,%.0f\n", name, centre.x, centre.y);
}

}  // namespace flashgs::viewer
