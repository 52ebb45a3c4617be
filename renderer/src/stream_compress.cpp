// gzip and zstd compression of whole buffers in memory (see stream_compress.h).
#include "stream_compress.h"

#include <algorithm>

#include "flashgs/error.h"

#ifdef FLASHGS_HAVE_ZLIB
#include <zlib.h>
#endif
#ifdef FLASHGS_HAVE_ZSTD
#include <zstd.h>
#endif

namespace flashgs {

std::vector<std::uint8_t> gzip_compress(const void* data, std::size_t size, const std::string& name) {
#ifdef FLASHGS_HAVE_ZLIB
  z_stream z{};
  // 15 bits of window plus 16: a gzip header and trailer around the deflate data.
  if (deflateInit2(&z, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw Error(name + ": zlib could not start a gzip stream");
  // zlib's own loop: feed at most 1 GB at a time, drain the output until deflate leaves room.
  std::vector<std::uint8_t> out;
  std::vector<std::uint8_t> piece(1 << 16);
  const auto* in = static_cast<const Bytef*>(data);
  std::size_t left = size;
  int flush = Z_NO_FLUSH;
  do {
    const uInt take = static_cast<uInt>(std::min<std::size_t>(left, std::size_t{1} << 30));
    z.next_in = const_cast<Bytef*>(in);
    z.avail_in = take;
    in += take;
    left -= take;
    flush = left == 0 ? Z_FINISH : Z_NO_FLUSH;
    do {
      z.next_out = piece.data();
      z.avail_out = static_cast<uInt>(piece.size());
      if (deflate(&z, flush) == Z_STREAM_ERROR) {
        deflateEnd(&z);
        throw Error(name + ": zlib failed while compressing");
      }
      out.insert(out.end(), piece.begin(), piece.end() - z.avail_out);
    } while (z.avail_out == 0);
  } while (flush != Z_FINISH);
  deflateEnd(&z);
  return out;
#else
  (void)data;
  (void)size;
  throw Error(name + ": this build has no zlib, so gzip-compressed SPZ cannot be written (install zlib1g-dev and rebuild)");
#endif
}

std::vector<std::uint8_t> zstd_compress(const void* data, std::size_t size, const std::string& name) {
#ifdef FLASHGS_HAVE_ZSTD
  std::vector<std::uint8_t> out(ZSTD_compressBound(size));
  const std::size_t written = ZSTD_compress(out.data(), out.size(), data, size, 12);
  if (ZSTD_isError(written)) throw Error(name + ": zstd failed (" + ZSTD_getErrorName(written) + ")");
  out.resize(written);
  return out;
#else
  (void)data;
  (void)size;
  throw Error(name + ": this build has no zstd, so SPZ version 4 cannot be written (install libzstd-dev and rebuild)");
#endif
}

}  // namespace flashgs
