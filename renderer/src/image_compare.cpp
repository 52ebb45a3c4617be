// Image metrics: PSNR, max abs error, fraction of pixels off by more than 1/255.
#include <cmath>
#include <limits>
#include <string>

#include "flashgs/error.h"
#include "flashgs/image.h"

namespace flashgs {

std::size_t count_non_finite(const Image& image) {
  std::size_t n = 0;
  for (float v : image.rgb) n += std::isfinite(v) ? 0 : 1;
  return n;
}

ImageDifference compare_images(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height)
    throw Error("cannot compare a " + std::to_string(a.width) + "x" + std::to_string(a.height) + " image with a " +
                std::to_string(b.width) + "x" + std::to_string(b.height) + " one");
  ImageDifference d;
  d.non_finite = count_non_finite(a) + count_non_finite(b);
  double sum_sq = 0;
  std::size_t pixels_over = 0;
  const std::size_t pixels = static_cast<std::size_t>(a.width) * a.height;
  for (std::size_t p = 0; p < pixels; ++p) {
    bool over = false;
    for (int ch = 0; ch < 3; ++ch) {
      const double diff = std::abs(static_cast<double>(a.rgb[p * 3 + ch]) - b.rgb[p * 3 + ch]);
      if (!std::isfinite(diff)) continue;
      sum_sq += diff * diff;
      if (diff > d.max_abs) d.max_abs = diff;
      over = over || diff > 1.0 / 255.0;
    }
    pixels_over += over ? 1 : 0;
  }
  d.mse = pixels ? sum_sq / (3.0 * pixels) : 0.0;
  d.psnr_db = d.mse > 0 ? 10.0 * std::log10(1.0 / d.mse) : std::numeric_limits<double>::infinity();
  d.fraction_over_1_255 = pixels ? static_cast<double>(pixels_over) / pixels : 0.0;
  return d;
}

}  // namespace flashgs
