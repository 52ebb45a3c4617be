// OpenImageIO behind a C interface (image_oiio_module.h), built as a module of its own that
// the programs load only when they read or write a PNG or EXR.
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <exception>
#include <mutex>
#include <string>

#include "image_oiio_module.h"

namespace {

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

int fail(const std::string& message, char* error, std::size_t error_size) {
  if (error_size > 0) std::snprintf(error, error_size, "%s", message.c_str());
  return 1;
}

}  // namespace

extern "C" int flashgs_oiio_can_write(const char* path) {
  try {
    const bool can = OIIO::ImageOutput::create(path) != nullptr;
    OIIO::geterror();  // clears the message, so that a later error does not carry it
    return can ? 1 : 0;
  } catch (const std::exception&) {
    return 0;
  }
}

extern "C" int flashgs_oiio_write(const char* path, int fd, const char* temp_path, int width, int height, int is_float,
                                  const void* pixels, int* write_errno, char* error, std::size_t error_size) {
  *write_errno = 0;
  try {
    DescriptorOutput proxy(fd, path);  // outlives `out`, whose destructor may still write
    auto out = OIIO::ImageOutput::create(path);
    if (!out) return fail(std::string(path) + ": cannot write this format (" + OIIO::geterror() + ")", error, error_size);
    const OIIO::TypeDesc type = is_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8;
    OIIO::ImageSpec spec(width, height, 3, type);
    // A plugin without I/O proxies opens the temporary by name; the caller still syncs and
    // checks it, but only its status tells of a write that failed.
    const bool proxied = out->supports("ioproxy") && out->set_ioproxy(&proxy);
    if (!out->open(proxied ? path : temp_path, spec)) return fail(std::string(path) + ": " + out->geterror(), error, error_size);
    bool ok = out->write_image(type, pixels);
    ok = out->close() && ok;
    *write_errno = proxy.error_number();
    if (!ok) return fail(std::string(path) + ": " + out->geterror(), error, error_size);
    return 0;
  } catch (const std::exception& e) {
    return fail(std::string(path) + ": " + e.what(), error, error_size);
  }
}

extern "C" int flashgs_oiio_read(const char* path, float* (*take)(void* context, int width, int height, int channels),
                                 void* context, char* error, std::size_t error_size) {
  try {
    auto in = OIIO::ImageInput::open(path);
    if (!in) return fail(std::string(path) + ": cannot read (" + OIIO::geterror() + ")", error, error_size);
    const OIIO::ImageSpec& spec = in->spec();
    float* pixels = take(context, spec.width, spec.height, spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels))
      return fail(std::string(path) + ": " + in->geterror(), error, error_size);
    return 0;
  } catch (const std::exception& e) {
    return fail(std::string(path) + ": " + e.what(), error, error_size);
  }
}
