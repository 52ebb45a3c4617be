// Image file IO: OpenImageIO when available, with the built-in PPM/PFM formats always.
#include "flashgs/image_io.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/file_write.h"
#include "flashgs/netpbm.h"

#ifdef FLASHGS_HAVE_OIIO
#include <OpenImageIO/filesystem.h>
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

#ifdef FLASHGS_HAVE_OIIO
// OpenImageIO's writes go through this proxy onto the output file's descriptor: the first
// error the system gives is kept, since a format plugin may not look at what a write returns
// (a PNG written to /dev/full, every byte of it refused, reported success).
class DescriptorOutput final : public OIIO::Filesystem::IOProxy {
 public:
  DescriptorOutput(int fd, const std::string& path) : IOProxy(path, Write), m_fd(fd) {}
  const char* proxytype() const override { return "flashgs_descriptor"; }
  size_t write(const void* buf, size_t size) override {
    const size_t n = pwrite(buf, size, m_pos);
    m_pos += static_cast<int64_t>(n);
    return n;
  }
  size_t pwrite(const void* buf, size_t size, int64_t offset) override {
    size_t done = 0;
    while (done < size) {
      const ssize_t n = ::pwrite(m_fd, static_cast<const char*>(buf) + done, size - done, offset + done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        const std::lock_guard<std::mutex> lock(m_mutex);
        if (!m_error) m_error = n < 0 ? errno : ENOSPC;
        break;
      }
      done += static_cast<size_t>(n);
    }
    const std::lock_guard<std::mutex> lock(m_mutex);
    m_size = std::max(m_size, static_cast<size_t>(offset) + done);
    return done;
  }
  size_t size() const override {
    const std::lock_guard<std::mutex> lock(m_mutex);
    return m_size;
  }
  // The errno value of the first failed write, 0 when none failed.
  int error_number() const {
    const std::lock_guard<std::mutex> lock(m_mutex);
    return m_error;
  }

 private:
  int m_fd;
  mutable std::mutex m_mutex;  // guards the two below (plugins may write from several threads)
  size_t m_size = 0;
  int m_error = 0;
};

// Encodes `image` with OpenImageIO into `file`; the format is the one `path`'s extension names.
void write_with_oiio(const Image& image, const std::string& path, const std::string& ext, OutputFile& file) {
  DescriptorOutput proxy(file.descriptor(), path);  // outlives `out`, whose destructor may still write
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw Error(path + ": cannot write this format (" + OIIO::geterror() + ")");
  const bool is_float = ext == "exr" || ext == "hdr" || ext == "tif" || ext == "tiff";
  OIIO::ImageSpec spec(image.width, image.height, 3, is_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
  // A plugin without I/O proxies opens the temporary by name; file.finish() still syncs and
  // checks it, but only its status tells of a write that failed.
  const bool proxied = out->supports("ioproxy") && out->set_ioproxy(&proxy);
  if (!out->open(proxied ? path : file.temp_path(), spec)) throw Error(path + ": " + out->geterror());
  bool ok;
  if (is_float) {
    ok = out->write_image(OIIO::TypeDesc::FLOAT, image.rgb.data());
  } else {
    std::vector<unsigned char> bytes(image.rgb.size());
    std::transform(image.rgb.begin(), image.rgb.end(), bytes.begin(), to_byte);
    ok = out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
  }
  ok = out->close() && ok;
  if (proxy.error_number()) file.write_failed(proxy.error_number());
  if (!ok) throw Error(path + ": " + out->geterror());
}
#endif

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
  write_file_atomically(path, [&](OutputFile& file) { write_with_oiio(image, path, ext, file); });
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
