// Writing an output file so that a failed or interrupted write never leaves half a file.
#pragma once

#include <filesystem>
#include <string>
#include <system_error>

#include "flashgs/error.h"

namespace flashgs::cli {

// Writes `path` through a temporary file beside it, renamed over it once complete: a failed
// or interrupted write leaves the old file (for `tile`, possibly its own source) intact.
template <class Write>
void write_atomically(const std::string& path, Write&& write) {
  const std::string partial = path + ".partial";
  std::error_code ec;
  try {
    write(partial);
  } catch (...) {
    std::filesystem::remove(partial, ec);
    throw;
  }
  std::filesystem::rename(partial, path, ec);
  if (ec) {
    std::filesystem::remove(partial, ec);
    throw Error(path + ": cannot replace it (" + ec.message() + ")");
  }
}

}  // namespace flashgs::cli
