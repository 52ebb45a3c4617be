// Float RGB to RGBA8, rounded and clamped, over the cores.
#include "rgba8_image.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace flashgs::viewer {

void to_rgba8(const Image& image, std::vector<std::uint8_t>& rgba) {
  const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
  rgba.resize(pixels * 4);
  // 8 Mpixel at 4K: spread over the cores when OpenMP is there (the CPU renderer uses it too).
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t i = 0; i < static_cast<std::ptrdiff_t>(pixels); ++i) {
    for (int c = 0; c < 3; ++c) {
      const float v = image.rgb[i * 3 + c];
      rgba[i * 4 + c] = !(v > 0.0f) ? 0 : static_cast<std::uint8_t>(std::lround(std::min(v, 1.0f) * 255.0f));
    }
    rgba[i * 4 + 3] = 255;
  }
}

}  // namespace flashgs::viewer
