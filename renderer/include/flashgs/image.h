// Image: a float RGB frame, row 0 at the top, and the metrics to compare two of them.
#pragma once

#include <cstddef>
#include <vector>

namespace flashgs {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<float> rgb;  // width * height * 3, row-major, top row first

  void resize(int w, int h) {
    width = w;
    height = h;
    rgb.assign(static_cast<std::size_t>(w) * h * 3, 0.0f);
  }
  float* pixel(int x, int y) { return &rgb[(static_cast<std::size_t>(y) * width + x) * 3]; }
  const float* pixel(int x, int y) const {
    return &rgb[(static_cast<std::size_t>(y) * width + x) * 3];
  }
};

struct ImageDifference {
  double psnr_db = 0;        // infinity when identical; peak value 1.0
  double max_abs = 0;        // largest |a - b| over all channels
  double mse = 0;
  double fraction_over_1_255 = 0;  // fraction of pixels with any channel off by > 1/255
  std::size_t non_finite = 0;      // NaN/Inf values in either image
};

// Compares two images of the same size; throws flashgs::Error otherwise.
ImageDifference compare_images(const Image& a, const Image& b);
std::size_t count_non_finite(const Image& image);

}  // namespace flashgs
