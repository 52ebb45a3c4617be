// Image files: PNG written through libpng; EXR/anything else, and reading PNG, through
// OpenImageIO when built with it; PPM/PFM always.
#pragma once

#include <string>

#include "flashgs/image.h"

namespace flashgs {

// Writes `image` to `path`; the extension picks the format. 8-bit formats get values clamped
// to [0, 1] and rounded; EXR/PFM keep the floats. Whole or not at all (write_file_atomically):
// throws flashgs::Error naming `path` on failure, a refused path or a failed write.
void write_image(const Image& image, const std::string& path);
// Reads an image as float RGB (8-bit formats scaled to [0, 1]).
Image read_image(const std::string& path);
// Whether write_image knows the format of `path`'s extension (checked before rendering, so
// that a typo in the name does not cost a whole render).
bool image_format_writable(const std::string& path);
// Whether OpenImageIO's formats are available (loads its module: 0.3-0.45 s at the first call).
bool image_io_has_oiio();
// Whether write_image writes PNG; without loading OpenImageIO where libpng does it.
bool image_io_writes_png();

}  // namespace flashgs
