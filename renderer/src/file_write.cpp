// Every output file is written through a temporary beside it, checked to the last byte, and
// renamed into place only when complete (see file_write.h).
#include "flashgs/file_write.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "flashgs/error.h"
#include "flashgs/file_access.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

// Large enough that a scene of millions of records costs few system calls.
constexpr std::size_t kBufferBytes = std::size_t{1} << 20;

// Where the bytes of `path` end up: the file a link names (check_output_file has seen that it
// is a regular file), else `path` itself.
std::string write_target(const std::string& path) {
  std::error_code ec;
  const fs::path real = fs::canonical(path, ec);
  return ec ? path : real.string();
}

// Creates a temporary beside `target` that nothing else can hold: O_EXCL, so that a file, link
// or FIFO already there under that name is never opened. Returns its descriptor.
int create_temporary(const std::string& path, const std::string& target, std::string* temp) {
  static std::atomic<unsigned> counter{0};
  for (int attempt = 0;; ++attempt) {
    *temp = target + ".partial-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
    const int fd = ::open(temp->c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOCTTY, 0666);
    if (fd >= 0) {
      // A replaced file keeps its permissions, as it would when written in place.
      struct stat old {};
      if (::stat(target.c_str(), &old) == 0) (void)::fchmod(fd, old.st_mode & 07777);
      return fd;
    }
    if (errno != EEXIST || attempt == 100)
      throw Error(path + ": cannot create a file beside it: " + std::strerror(errno));
  }
}

}  // namespace

OutputFile::OutputFile(std::string path, std::string temp, int fd)
    : m_path(std::move(path)), m_temp(std::move(temp)), m_fd(fd) {}

OutputFile::~OutputFile() {
  if (m_fd >= 0) ::close(m_fd);
}

void OutputFile::write_failed(int error) const {
  throw Error(m_path + ": write error: " + std::strerror(error));
}

void OutputFile::write(const void* data, std::size_t size) {
  const char* bytes = static_cast<const char*>(data);
  if (m_buffer.size() + size > kBufferBytes) {
    write_all(m_buffer.data(), m_buffer.size());
    m_buffer.clear();
  }
  if (size >= kBufferBytes) write_all(bytes, size);  // large blocks go straight through
  else m_buffer.append(bytes, size);
}

void OutputFile::write_all(const char* bytes, std::size_t size) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(m_fd, bytes + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) write_failed(errno);
    if (n == 0) write_failed(ENOSPC);  // a regular file that takes nothing is full
    done += static_cast<std::size_t>(n);
  }
}

void OutputFile::finish() {
  write_all(m_buffer.data(), m_buffer.size());
  m_buffer.clear();
  if (::fsync(m_fd) != 0) write_failed(errno);
  const int fd = m_fd;
  m_fd = -1;
  if (::close(fd) != 0) write_failed(errno);
}

void write_file_atomically(const std::string& path, const std::function<void(OutputFile&)>& write) {
  check_output_file(path);
  const std::string target = write_target(path);
  std::string temp;
  const int fd = create_temporary(path, target, &temp);
  try {
    OutputFile file(path, temp, fd);
    write(file);
    file.finish();
  } catch (...) {
    std::remove(temp.c_str());
    throw;
  }
  if (std::rename(temp.c_str(), target.c_str()) != 0) {
    const int error = errno;
    std::remove(temp.c_str());
    throw Error(path + ": cannot replace it: " + std::strerror(error));
  }
}

void write_file_atomically(const std::string& path, const std::string& bytes) {
  write_file_atomically(path, [&](OutputFile& file) { file.write(bytes); });
}

}  // namespace flashgs
