// Counts as the viewer shows them: "950", "12.3k", "1.54M".
#pragma once

#include <string>

namespace flashgs::viewer {

std::string human_count(double v);

}  // namespace flashgs::viewer
