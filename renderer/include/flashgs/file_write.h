// Writing an output file whole or not at all: every byte, the flush to the disk and the close
// checked, the file renamed into place only once complete.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

namespace flashgs {

// The file write_file_atomically hands its writer: a temporary beside the target, buffered.
// Each error names the path as the caller gave it (not the temporary) and the system's reason.
class OutputFile {
 public:
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  ~OutputFile();

  // Appends `size` bytes; throws flashgs::Error "<path>: write error: <reason>" (a full disk,
  // a file-size limit) when the system refuses them.
  void write(const void* data, std::size_t size);
  void write(const std::string& text) { write(text.data(), text.size()); }

  // The temporary's descriptor, for a library that writes every byte itself at offsets of its
  // own (OpenImageIO's I/O proxy); not to be mixed with write().
  int descriptor() const { return m_fd; }
  // The temporary's name, for a library that can only open a file by name.
  const std::string& temp_path() const { return m_temp; }
  // Throws the write error above for `error` (an errno value) that such a library met.
  [[noreturn]] void write_failed(int error) const;

 private:
  friend void write_file_atomically(const std::string& path, const std::function<void(OutputFile&)>& write);
  OutputFile(std::string path, std::string temp, int fd);
  void write_all(const char* bytes, std::size_t size);
  // Flushes, syncs to the disk and closes: a full disk or an I/O error shows here at the latest.
  void finish();

  std::string m_path;  // as the caller named it, for messages
  std::string m_temp;
  int m_fd;
  std::string m_buffer;
};

// Writes `path` through `write`: check_output_file(path) (file_access.h) first, nothing created
// when it throws; then the bytes go to a temporary in the target's folder (the folder of what a
// symbolic link names: the link stays), which is synced and renamed over the target once
// `write` returned and every write succeeded. On any failure the temporary is removed and the
// target left as it was; the flashgs::Error (naming `path`) or `write`'s own exception propagates.
void write_file_atomically(const std::string& path, const std::function<void(OutputFile&)>& write);
// The same for content that is at hand as a whole.
void write_file_atomically(const std::string& path, const std::string& bytes);

}  // namespace flashgs
