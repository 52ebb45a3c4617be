// PNG through libpng's simplified API: the image is encoded in memory, then written whole.
#include "png_write.h"

#include <png.h>

#include <algorithm>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/netpbm.h"

namespace flashgs {

void write_png(const Image& image, const std::string& path, OutputFile& file) {
  std::vector<unsigned char> pixels(image.rgb.size());
  std::transform(image.rgb.begin(), image.rgb.end(), pixels.begin(), to_byte);
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(image.width);
  png.height = static_cast<png_uint_32>(image.height);
  png.format = PNG_FORMAT_RGB;
  png_alloc_size_t size = 0;
  // The first call sizes the encoding, the second makes it.
  if (!png_image_write_to_memory(&png, nullptr, &size, 0, pixels.data(), 0, nullptr))
    throw Error(path + ": PNG encoding failed: " + png.message);
  std::vector<unsigned char> encoded(size);
  if (!png_image_write_to_memory(&png, encoded.data(), &size, 0, pixels.data(), 0, nullptr))
    throw Error(path + ": PNG encoding failed: " + png.message);
  file.write(encoded.data(), size);
}

}  // namespace flashgs
