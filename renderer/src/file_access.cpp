// The file-type checks and the non-blocking whole-file read behind every scene and camera file,
// and the check of every output file.
#include "flashgs/file_access.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "flashgs/error.h"
#include "flashgs/load_progress.h"
#include "huge_pages.h"

namespace flashgs {
namespace {

// The name may come from a file (a texture or chunk named in JSON) or a user's argument.
[[noreturn]] void fail(const std::string& path, const std::string& problem) {
  throw Error(printable_file_text(path, kMaxPrintedPathBytes) + ": " + problem);
}

// Why stat() or open() failed, in words.
[[noreturn]] void fail_to_open(const std::string& path, int error) {
  struct stat link {};
  switch (error) {
    case ENOENT:
      if (::lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode))
        fail(path, "cannot open: a symbolic link whose target does not exist");
      fail(path, "cannot open: no such file or folder");
    case ENOTDIR: fail(path, "cannot open: a part of the path is not a folder");
    case ELOOP: fail(path, "cannot open: a loop of symbolic links");
    case EACCES:
    case EPERM: fail(path, "cannot open: permission denied");
    case ENAMETOOLONG: fail(path, "cannot open: the path is too long");
    default: fail(path, std::string("cannot open: ") + std::strerror(error));
  }
}

void check_regular(const std::string& path, mode_t mode) {
  if (S_ISREG(mode)) return;
  if (S_ISDIR(mode)) fail(path, "is a folder, not a file");
  if (S_ISFIFO(mode)) fail(path, "is a FIFO (named pipe), not a regular file");
  if (S_ISCHR(mode) || S_ISBLK(mode)) fail(path, "is a device, not a regular file");
  if (S_ISSOCK(mode)) fail(path, "is a socket, not a regular file");
  fail(path, "is not a regular file");
}

struct stat stat_or_fail(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) fail_to_open(path, errno);
  return st;
}

std::string megabytes(std::size_t bytes) { return std::to_string(bytes / 1000000 + (bytes % 1000000 != 0)) + " MB"; }

// Bytes read between two progress reports: small enough that a progress bar moves, large
// enough that the checks cost nothing.
constexpr std::size_t kProgressChunk = 4 << 20;

// Reads until `size` bytes or the end of the file; returns the bytes read. With `progress`,
// in chunks, reporting after each and stopping on a cancel request.
std::size_t read_fully(const std::string& path, int fd, char* into, std::size_t size,
                       LoadProgress* progress = nullptr) {
  std::size_t filled = 0;
  while (filled < size) {
    if (progress && progress->cancel_requested.load(std::memory_order_relaxed)) throw LoadCancelled(path);
    const std::size_t want = progress ? std::min(size - filled, kProgressChunk) : size - filled;
    const ssize_t n = ::read(fd, into + filled, want);
    if (n == 0) break;
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail(path, std::string("read error: ") + std::strerror(errno));
    filled += static_cast<std::size_t>(n);
    if (progress) progress->bytes_done.fetch_add(static_cast<std::uint64_t>(n), std::memory_order_relaxed);
  }
  return filled;
}

// Closes the descriptor on every path out of read_regular_file.
struct FileDescriptor {
  int fd;
  ~FileDescriptor() { ::close(fd); }
};

// Opens the regular file at `path` for reading, checked before and after opening; `st` is its status.
int open_regular(const std::string& path, struct stat* st) {
  check_regular(path, stat_or_fail(path).st_mode);
  // O_NONBLOCK: should the path become a FIFO after the check, open() still returns at once.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) fail_to_open(path, errno);
  if (::fstat(fd, st) != 0) {
    const int error = errno;
    ::close(fd);
    fail_to_open(path, error);
  }
  if (!S_ISREG(st->st_mode)) {
    ::close(fd);
    check_regular(path, st->st_mode);  // throws
  }
  return fd;
}

}  // namespace

PathKind path_kind(const std::string& path) {
  const struct stat st = stat_or_fail(path);
  if (S_ISREG(st.st_mode)) return PathKind::regular_file;
  if (S_ISDIR(st.st_mode)) return PathKind::folder;
  return PathKind::other;
}

void check_regular_file(const std::string& path) { check_regular(path, stat_or_fail(path).st_mode); }

void check_output_file(const std::string& path) {
  if (path.empty()) throw Error("the output path is empty");
  namespace fs = std::filesystem;
  struct stat st {};
  fs::path folder;
  if (::stat(path.c_str(), &st) == 0) {
    check_regular(path, st.st_mode);
    if (::access(path.c_str(), W_OK) != 0) fail(path, std::string("the file is not writable: ") + std::strerror(errno));
    // The file is replaced beside what a link names, so that the link stays.
    std::error_code ec;
    folder = fs::canonical(path, ec).parent_path();
    if (ec) fail(path, "cannot resolve its path: " + ec.message());
  } else if (errno == ENOENT) {
    struct stat link {};
    if (::lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode))
      fail(path, "a symbolic link whose target does not exist");
    folder = fs::path(path).parent_path();
    if (folder.empty()) folder = ".";
    struct stat dir {};
    if (::stat(folder.c_str(), &dir) != 0 || !S_ISDIR(dir.st_mode))
      fail(path, "the folder " + folder.string() + " does not exist");
  } else {
    fail_to_open(path, errno);
  }
  if (::access(folder.c_str(), W_OK) != 0) fail(path, "the folder " + folder.string() + " is not writable");
}

std::vector<char> read_file_start(const std::string& path, std::size_t max_bytes) {
  struct stat st {};
  const FileDescriptor file{open_regular(path, &st)};
  // Not sized by st_size: files of /proc and the like report 0 yet have content.
  std::vector<char> bytes(max_bytes);
  bytes.resize(read_fully(path, file.fd, bytes.data(), bytes.size()));
  return bytes;
}

std::vector<char> read_regular_file(const std::string& path, std::size_t max_bytes, LoadProgress* progress) {
  struct stat st {};
  const FileDescriptor file{open_regular(path, &st)};
  const auto size = static_cast<std::size_t>(st.st_size);
  if (size > max_bytes) fail(path, "the file is " + megabytes(size) + ", more than the " + megabytes(max_bytes) +
                                       " this kind of file may have");
  if (progress) {
    progress->bytes_done.store(0, std::memory_order_relaxed);
    progress->bytes_total.store(size, std::memory_order_relaxed);
  }
  std::vector<char> bytes;
  bytes.reserve(size);
  advise_huge_pages(bytes.data(), size);  // before the first touch: an 80 MB scene read 3-5x faster
  bytes.resize(size);
  const std::size_t filled = read_fully(path, file.fd, bytes.data(), size, progress);
  if (filled < size) {  // the file shrank since fstat
    bytes.resize(filled);
    return bytes;
  }
  // Files of /proc and the like report size 0 yet have content, and a file may have grown.
  char chunk[1 << 16];
  while (const std::size_t n = read_fully(path, file.fd, chunk, sizeof chunk, progress)) {
    if (n > max_bytes - bytes.size())
      fail(path, "the file holds more than the " + megabytes(max_bytes) + " this kind of file may have");
    bytes.insert(bytes.end(), chunk, chunk + n);
  }
  if (progress) progress->bytes_total.store(bytes.size(), std::memory_order_relaxed);
  return bytes;
}

}  // namespace flashgs
