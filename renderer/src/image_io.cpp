// Image file IO: PNG written through libpng, EXR/anything else (and reading PNG) through the
// OpenImageIO module when built with it (loaded at the first such use), PPM/PFM always.
#include "flashgs/image_io.h"

#include <dlfcn.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/file_write.h"
#include "flashgs/netpbm.h"
#include "image_oiio_module.h"
#ifdef FLASHGS_HAVE_PNG
#include "png_write.h"
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

// The OpenImageIO module's functions, or why there are none.
struct OiioModule {
  decltype(&flashgs_oiio_can_write) can_write = nullptr;
  decltype(&flashgs_oiio_write) write = nullptr;
  decltype(&flashgs_oiio_read) read = nullptr;
  std::string why_not;  // empty when loaded
};

OiioModule load_oiio_module() {
  OiioModule m;
#ifdef FLASHGS_OIIO_MODULE
  // Where the build put it, else beside the running program (a copied build tree).
  std::vector<std::string> places = {FLASHGS_OIIO_MODULE};
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) places.push_back((self.parent_path() / std::filesystem::path(FLASHGS_OIIO_MODULE).filename()).string());
  void* handle = nullptr;
  for (const std::string& place : places)
    if ((handle = dlopen(place.c_str(), RTLD_NOW | RTLD_LOCAL))) break;
  if (!handle) {
    const char* why = dlerror();
    m.why_not = std::string("the OpenImageIO module ") + FLASHGS_OIIO_MODULE + " did not load (" + (why ? why : "?") + ")";
    return m;
  }
  m.can_write = reinterpret_cast<decltype(m.can_write)>(dlsym(handle, "flashgs_oiio_can_write"));
  m.write = reinterpret_cast<decltype(m.write)>(dlsym(handle, "flashgs_oiio_write"));
  m.read = reinterpret_cast<decltype(m.read)>(dlsym(handle, "flashgs_oiio_read"));
  if (!m.can_write || !m.write || !m.read) {
    m = OiioModule{};
    m.why_not = std::string("the OpenImageIO module ") + FLASHGS_OIIO_MODULE + " lacks its functions";
  }
#else
  m.why_not = "this build has none";
#endif
  return m;
}

// Loaded once, at the first use (thread-safe).
const OiioModule& oiio() {
  static const OiioModule module = load_oiio_module();
  return module;
}

// Encodes `image` with OpenImageIO into `file`; the format is the one `path`'s extension names.
void write_with_oiio(const OiioModule& m, const Image& image, const std::string& path, const std::string& ext,
                     OutputFile& file) {
  const bool is_float = ext == "exr" || ext == "hdr" || ext == "tif" || ext == "tiff";
  std::vector<unsigned char> bytes;
  if (!is_float) {
    bytes.resize(image.rgb.size());
    std::transform(image.rgb.begin(), image.rgb.end(), bytes.begin(), to_byte);
  }
  const void* pixels = is_float ? static_cast<const void*>(image.rgb.data()) : bytes.data();
  char error[1024] = "";
  int write_errno = 0;
  const int status = m.write(path.c_str(), file.descriptor(), file.temp_path().c_str(), image.width, image.height,
                             is_float ? 1 : 0, pixels, &write_errno, error, sizeof error);
  if (write_errno) file.write_failed(write_errno);
  if (status != 0) throw Error(error);
}

}  // namespace

bool image_io_has_oiio() { return oiio().why_not.empty(); }

bool image_io_writes_png() {
#ifdef FLASHGS_HAVE_PNG
  return true;
#else
  return image_io_has_oiio();
#endif
}

bool image_format_writable(const std::string& path) {
  const std::string ext = extension_of(path);
  if (ext == "ppm" || ext == "pfm") return true;
#ifdef FLASHGS_HAVE_PNG
  if (ext == "png") return true;
#endif
  const OiioModule& m = oiio();
  return m.why_not.empty() && !ext.empty() && m.can_write(path.c_str()) != 0;
}

void write_image(const Image& image, const std::string& path) {
  const std::string ext = extension_of(path);
  if (ext == "ppm") return write_ppm(image, path);
  if (ext == "pfm") return write_pfm(image, path);
#ifdef FLASHGS_HAVE_PNG
  if (ext == "png") return write_file_atomically(path, [&](OutputFile& file) { write_png(image, path, file); });
#endif
  const OiioModule& m = oiio();
  if (!m.why_not.empty()) throw Error(path + ": ." + ext + " needs OpenImageIO: " + m.why_not + "; use .ppm or .pfm");
  write_file_atomically(path, [&](OutputFile& file) { write_with_oiio(m, image, path, ext, file); });
}

Image read_image(const std::string& path) {
  const std::string ext = extension_of(path);
  if (ext == "ppm" || ext == "pfm") return read_netpbm(path);
  const OiioModule& m = oiio();
  if (!m.why_not.empty()) throw Error(path + ": reading ." + ext + " needs OpenImageIO: " + m.why_not);
  struct Buffer {
    std::vector<float> pixels;
    int width = 0, height = 0, channels = 0;
  } buffer;
  auto take = [](void* context, int width, int height, int channels) -> float* {
    Buffer& b = *static_cast<Buffer*>(context);
    b.width = width;
    b.height = height;
    b.channels = channels;
    b.pixels.assign(static_cast<std::size_t>(width) * height * channels, 0.0f);
    return b.pixels.data();
  };
  char error[1024] = "";
  if (m.read(path.c_str(), take, &buffer, error, sizeof error) != 0) throw Error(error);
  Image image;
  image.resize(buffer.width, buffer.height);
  for (std::size_t p = 0; p < static_cast<std::size_t>(buffer.width) * buffer.height; ++p)
    for (int ch = 0; ch < 3; ++ch)
      image.rgb[p * 3 + ch] = buffer.pixels[p * buffer.channels + std::min(ch, buffer.channels - 1)];
  return image;
}

}  // namespace flashgs
