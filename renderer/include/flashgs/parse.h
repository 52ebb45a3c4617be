// Parsing of values typed by a user (command line, viewer fields): strict, range checked.
#pragma once

#include <string>

namespace flashgs {

// The largest image side any parser accepts (the frame's memory is checked separately).
constexpr int kMaxImageSide = 65536;

struct Resolution {
  int width = 0;
  int height = 0;
};

// "1920x1080" (or "1920X1080") -> {1920, 1080}: digits only, 1 <= W, H <= max_side. Throws
// flashgs::Error("resolution \"<text>\": expected WxH with 1 <= W, H <= <max_side>") otherwise,
// including on values that overflow an int (no wrap-around as with sscanf).
Resolution parse_resolution(const std::string& text, int max_side = kMaxImageSide);

}  // namespace flashgs
