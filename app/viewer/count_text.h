// Counts and sizes as the viewer shows them.
#pragma once

#include <string>

namespace flashgs::viewer {

// "950", "12.3k", "1.54M".
std::string human_count(double v);

// A frame's size: "1920x1080".
std::string size_text(int width, int height);

}  // namespace flashgs::viewer
