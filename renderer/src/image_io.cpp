// Image file IO: OpenImageIO when available, with the built-in PPM/PFM formats always.
#include "flashgs/image_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/netpbm.h"

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

}  // namespace

bool image_io_has_oiio() {
#ifdef FLASHGS_HAVE_OIIO
  return true;
#else
  return false;
#endif
}

bool image_format_writable(const std::string& path) {
  const std::string ext = extension_of(path);
  if (ext == "ppm" || ext == "pfm") return true;
#ifdef FLASHGS_HAVE_OIIO
  if (!ext.empty() && OIIO::ImageOutput::create(path)) return true;
  OIIO::geterror();  // clears the message, so that a later error does not carry it
  return false;
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
