// Image file IO: OpenImageIO when available, plus built-in PPM (8-bit) and PFM (float).
#include "flashgs/image_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

#include "flashgs/error.h"

#ifdef FLASHGS_HAVE_OIIO
#include <OpenImageIO/imageio.h>
#endif

namespace flashgs {
namespace {

std::string extension_of(const std::string& path) {
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos) return "";
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

unsigned char to_byte(float v) {
  if (!(v > 0.0f)) return 0;  // NaN -> 0
  return static_cast<unsigned char>(std::lround(std::min(v, 1.0f) * 255.0f));
}

void write_ppm(const Image& image, const std::string& path) {
  std::ofstream file(path, std::ios::binary);
  if (!file) throw Error(path + ": cannot open for writing");
  file << "P6\n" << image.width << " " << image.height << "\n255\n";
  std::vector<unsigned char> bytes(image.rgb.size());
  std::transform(image.rgb.begin(), image.rgb.end(), bytes.begin(), to_byte);
  file.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!file) throw Error(path + ": write error");
}

void write_pfm(const Image& image, const std::string& path) {
  std::ofstream file(path, std::ios::binary);
  if (!file) throw Error(path + ": cannot open for writing");
  file << "PF\n" << image.width << " " << image.height << "\n-1.0\n";  // little endian
  for (int y = image.height - 1; y >= 0; --y)  // PFM stores the bottom row first
    file.write(reinterpret_cast<const char*>(image.pixel(0, y)), static_cast<std::streamsize>(image.width * 3 * 4));
  if (!file) throw Error(path + ": write error");
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

}  // namespace

bool image_io_has_oiio() {
#ifdef FLASHGS_HAVE_OIIO
  return true;
#else
  return false;
#endif
}

void write_image(const Image& image, const std::string& path) {
  const std::string ext = extension_of(path);
  if (ext == "ppm") return write_ppm(image, path);
  if (ext == "pfm") return write_pfm(image, path);
#ifdef FLASHGS_HAVE_OIIO
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw Error(path + ": cannot write this format (" + OIIO::geterror() + ")");
  const bool is_float = ext == "exr" || ext == "hdr" || ext == "tif" || ext == "tiff";
  OIIO::ImageSpec spec(image.width, image.height, 3, is_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
  if (!out->open(path, spec)) throw Error(path + ": " + out->geterror());
  bool ok;
  if (is_float) {
    ok = out->write_image(OIIO::TypeDesc::FLOAT, image.rgb.data());
  } else {
    std::vector<unsigned char> bytes(image.rgb.size());
    std::transform(image.rgb.begin(), image.rgb.end(), bytes.begin(), to_byte);
    ok = out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
  }
  if (!ok || !out->close()) throw Error(path + ": " + out->geterror());
#else
  throw Error(path + ": ." + ext + " needs OpenImageIO, which this build lacks; use .ppm or .pfm");
#endif
}

Image read_image(const std::string& path) {
  const std::string ext = extension_of(path);
  if (ext == "ppm" || ext == "pfm") return read_netpbm(path);
#ifdef FLASHGS_HAVE_OIIO
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw Error(path + ": cannot read (" + OIIO::geterror() + ")");
  const OIIO::ImageSpec& spec = in->spec();
  std::vector<float> pixels(static_cast<std::size_t>(spec.width) * spec.height * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data()))
    throw Error(path + ": " + in->geterror());
  Image image;
  image.resize(spec.width, spec.height);
  for (std::size_t p = 0; p < static_cast<std::size_t>(spec.width) * spec.height; ++p)
    for (int ch = 0; ch < 3; ++ch)
      image.rgb[p * 3 + ch] = pixels[p * spec.nchannels + std::min(ch, spec.nchannels - 1)];
  return image;
#else
  throw Error(path + ": reading ." + ext + " needs OpenImageIO, which this build lacks");
#endif
}

}  // namespace flashgs
