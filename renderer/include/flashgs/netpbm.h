// Built-in image files with no dependency: PPM (8-bit RGB) and PFM (float RGB).
#pragma once

#include <string>

#include "flashgs/image.h"

namespace flashgs {

// The writers go through write_file_atomically: a file whole or not at all.
void write_ppm(const Image& image, const std::string& path);  // clamped to [0, 1], rounded
void write_pfm(const Image& image, const std::string& path);  // floats kept
Image read_netpbm(const std::string& path);                   // P6 or PF
// [0, 1] -> 0..255 with rounding; NaN -> 0.
unsigned char to_byte(float v);

}  // namespace flashgs
