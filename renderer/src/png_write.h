// PNG files written through libpng, so that the programs' commonest image format needs no
// OpenImageIO module (whose ~260 libraries cost a viewer 0.3-0.45 s before its first frame).
#pragma once

#include <string>

#include "flashgs/file_write.h"
#include "flashgs/image.h"

namespace flashgs {

// Encodes `image` as 8-bit RGB PNG (values clamped to [0, 1] and rounded) into `file`; throws
// flashgs::Error naming `path` when libpng refuses it.
void write_png(const Image& image, const std::string& path, OutputFile& file);

}  // namespace flashgs
