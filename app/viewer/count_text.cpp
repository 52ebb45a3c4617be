// Counts and sizes as the viewer shows them (see count_text.h).
#include "count_text.h"

#include <cstdio>

namespace flashgs::viewer {

std::string human_count(double v) {
  char text[32];
  if (v >= 1e6) std::snprintf(text, sizeof text, "%.2fM", v / 1e6);
  else if (v >= 1e4) std::snprintf(text, sizeof text, "%.1fk", v / 1e3);
  else std::snprintf(text, sizeof text, "%.0f", v);
  return text;
}

std::string size_text(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

}  // namespace flashgs::viewer
