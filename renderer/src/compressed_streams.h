// Bounded decompression of the gzip and zstd streams inside splat files: output grows only as
// real data arrives and never past the size the caller expects, so a lying header or a
// compression bomb gets a message instead of a huge allocation.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "flashgs/load_progress.h"

namespace flashgs {

// Inflates a gzip stream held in memory, a piece at a time (the SPZ header comes first and
// says how much follows). Messages name `name`.
class GzipReader {
 public:
  GzipReader(const unsigned char* data, std::size_t size, const std::string& name, LoadProgress* progress);
  ~GzipReader();
  GzipReader(const GzipReader&) = delete;
  GzipReader& operator=(const GzipReader&) = delete;
  // Appends exactly `n` inflated bytes to `out`; throws flashgs::Error when the stream ends or
  // is corrupt first (`what` names the part being read, for the message).
  void read(std::size_t n, std::vector<std::uint8_t>& out, const std::string& what);
  // Throws unless the stream ends here: more data means a wrong count or a bomb.
  void expect_end(const std::string& expected_total);

 private:
  struct State;
  std::unique_ptr<State> m_state;
};

// Up to the first `n` bytes a gzip stream inflates to (fewer when it is corrupt or shorter);
// empty without zlib. For recognising a file by what its stream starts with; `corrupt`, when
// given, says whether zlib found the stream corrupt (a bad gzip header or deflate data).
std::vector<std::uint8_t> gzip_peek(const unsigned char* data, std::size_t size, std::size_t n,
                                    bool* corrupt = nullptr);

// Decompresses one zstd frame to exactly `expected` bytes; throws flashgs::Error naming
// `name` and `what` when it is corrupt, shorter, or would grow past `expected`.
std::vector<std::uint8_t> zstd_decompress_exact(const unsigned char* data, std::size_t size, std::size_t expected,
                                                const std::string& name, const std::string& what,
                                                LoadProgress* progress);

// Whether this build can read each kind of stream (the libraries are optional).
bool have_gzip_support();
bool have_zstd_support();

}  // namespace flashgs
