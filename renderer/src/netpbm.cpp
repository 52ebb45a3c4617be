// Built-in PPM (8-bit) and PFM (float) image files.
#include "flashgs/netpbm.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/file_write.h"

namespace flashgs {

unsigned char to_byte(float v) {
  if (!(v > 0.0f)) return 0;  // NaN -> 0
  return static_cast<unsigned char>(std::lround(std::min(v, 1.0f) * 255.0f));
}

void write_ppm(const Image& image, const std::string& path) {
  std::vector<unsigned char> bytes(image.rgb.size());
  std::transform(image.rgb.begin(), image.rgb.end(), bytes.begin(), to_byte);
  write_file_atomically(path, [&](OutputFile& file) {
    file.write("P6\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n255\n");
    file.write(bytes.data(), bytes.size());
  });
}

void write_pfm(const Image& image, const std::string& path) {
  write_file_atomically(path, [&](OutputFile& file) {
    file.write("PF\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n-1.0\n");  // little endian
    for (int y = image.height - 1; y >= 0; --y)  // PFM stores the bottom row first
      file.write(image.pixel(0, y), static_cast<std::size_t>(image.width) * 3 * sizeof(float));
  });
}

Image read_netpbm(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw Error(path + ": cannot open");
  std::string magic;
  int w = 0, h = 0;
  double scale = 0;
  file >> magic >> w >> h >> scale;
  file.get();
  if ((magic != "P6" && magic != "PF") || w <= 0 || h <= 0 || w > 65536 || h > 65536)
    throw Error(path + ": not a binary PPM/PFM image");
  Image image;
  image.resize(w, h);
  if (magic == "P6") {
    std::vector<unsigned char> bytes(image.rgb.size());
    file.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    for (std::size_t i = 0; i < bytes.size(); ++i) image.rgb[i] = bytes[i] / 255.0f;
  } else {
    for (int y = h - 1; y >= 0; --y)
      file.read(reinterpret_cast<char*>(image.pixel(0, y)), static_cast<std::streamsize>(w * 3 * 4));
  }
  if (!file) throw Error(path + ": truncated image");
  return image;
}

}  // namespace flashgs
