// The frame's conversion to texture bytes: a float image as RGBA8, without GL (a comparison converts its images off the UI thread).
#pragma once

#include <cstdint>
#include <vector>

#include "flashgs/image.h"

namespace flashgs::viewer {

// A float RGB image (top row first) as RGBA8 bytes, rounded as write_image's 8-bit path does
// (so a CPU-path screenshot equals the CLI's PNG).
void to_rgba8(const Image& image, std::vector<std::uint8_t>& rgba);

}  // namespace flashgs::viewer
