// gzip (zlib) and zstd decompression with a hard cap on the output and progress as input is consumed.
#include "compressed_streams.h"

#include <algorithm>
#include <climits>

#include "flashgs/error.h"

#ifdef FLASHGS_HAVE_ZLIB
#include <zlib.h>
#endif
#ifdef FLASHGS_HAVE_ZSTD
#include <zstd.h>
#include <zstd_errors.h>
#endif

namespace flashgs {
namespace {

// Output grows by at most this much per step, so memory follows the data actually decoded.
constexpr std::size_t kGrowStep = std::size_t{4} << 20;

[[noreturn]] void fail(const std::string& name, const std::string& problem) { throw Error(name + ": " + problem); }

void add_progress(LoadProgress* progress, std::size_t consumed, const std::string& name) {
  if (!progress) return;
  progress->bytes_done.fetch_add(consumed, std::memory_order_relaxed);
  if (progress->cancel_requested.load(std::memory_order_relaxed)) throw LoadCancelled(name);
}

}  // namespace

#ifdef FLASHGS_HAVE_ZLIB

struct GzipReader::State {
  z_stream stream{};
  bool ended = false;
  std::string name;
  LoadProgress* progress = nullptr;
};

GzipReader::GzipReader(const unsigned char* data, std::size_t size, const std::string& name, LoadProgress* progress)
    : m_state(std::make_unique<State>()) {
  m_state->name = name;
  m_state->progress = progress;
  m_state->stream.next_in = const_cast<Bytef*>(data);
  m_state->stream.avail_in = static_cast<uInt>(std::min<std::size_t>(size, UINT_MAX));
  if (size > UINT_MAX) fail(name, "the file is larger than 4 GB, more than a gzip stream here may be");
  // 16 + MAX_WBITS: a gzip header and trailer, not a raw zlib stream.
  if (inflateInit2(&m_state->stream, 16 + MAX_WBITS) != Z_OK) fail(name, "cannot start the gzip decoder");
}

GzipReader::~GzipReader() { inflateEnd(&m_state->stream); }

void GzipReader::read(std::size_t n, std::vector<std::uint8_t>& out, const std::string& what) {
  State& s = *m_state;
  std::size_t remaining = n;
  while (remaining > 0) {
    if (s.ended)
      fail(s.name, "the gzip stream ends inside the " + what + " (truncated file or wrong Gaussian count)");
    const std::size_t step = std::min({remaining, kGrowStep, static_cast<std::size_t>(UINT_MAX)});
    const std::size_t before = out.size();
    out.resize(before + step);
    s.stream.next_out = out.data() + before;
    s.stream.avail_out = static_cast<uInt>(step);
    const uInt in_before = s.stream.avail_in;
    const int result = inflate(&s.stream, Z_NO_FLUSH);
    const std::size_t produced = step - s.stream.avail_out;
    out.resize(before + produced);
    remaining -= produced;
    add_progress(s.progress, in_before - s.stream.avail_in, s.name);
    if (result == Z_STREAM_END) {
      s.ended = true;
    } else if (result == Z_BUF_ERROR && s.stream.avail_in == 0) {
      fail(s.name, "the gzip stream is cut short inside the " + what + " (truncated file)");
    } else if (result != Z_OK) {
      fail(s.name, std::string("the gzip data is corrupt in the ") + what + " (" +
                       (s.stream.msg ? s.stream.msg : "zlib error " + std::to_string(result)) + ")");
    }
  }
}

void GzipReader::expect_end(const std::string& expected_total) {
  State& s = *m_state;
  if (!s.ended) {
    unsigned char probe[1];
    s.stream.next_out = probe;
    s.stream.avail_out = 1;
    const uInt in_before = s.stream.avail_in;
    const int result = inflate(&s.stream, Z_NO_FLUSH);
    add_progress(s.progress, in_before - s.stream.avail_in, s.name);
    if (s.stream.avail_out == 0)
      fail(s.name, "the gzip stream holds more than the " + expected_total +
                       " the header declares (a wrong count, or a gzip bomb)");
    if (result != Z_STREAM_END)
      fail(s.name, "the gzip stream has no proper end after the " + expected_total + " (truncated or corrupt file)");
    s.ended = true;
  }
  if (s.stream.avail_in != 0)
    fail(s.name, std::to_string(s.stream.avail_in) + " bytes follow the gzip stream (a second stream or junk)");
}

std::vector<std::uint8_t> gzip_peek(const unsigned char* data, std::size_t size, std::size_t n, bool* corrupt) {
  std::vector<std::uint8_t> out(n);
  z_stream stream{};
  if (corrupt) *corrupt = false;
  if (inflateInit2(&stream, 16 + MAX_WBITS) != Z_OK) return {};
  stream.next_in = const_cast<Bytef*>(data);
  stream.avail_in = static_cast<uInt>(std::min<std::size_t>(size, UINT_MAX));
  stream.next_out = out.data();
  stream.avail_out = static_cast<uInt>(n);
  int result = Z_OK;
  while (stream.avail_out > 0 && (result = inflate(&stream, Z_NO_FLUSH)) == Z_OK) {
  }
  if (corrupt) *corrupt = result == Z_DATA_ERROR;
  out.resize(n - stream.avail_out);
  inflateEnd(&stream);
  return out;
}

bool have_gzip_support() { return true; }

#else

struct GzipReader::State {};
GzipReader::GzipReader(const unsigned char*, std::size_t, const std::string& name, LoadProgress*) {
  fail(name, "this build has no zlib, so gzip-compressed files cannot be read (install zlib1g-dev and rebuild)");
}
GzipReader::~GzipReader() = default;
void GzipReader::read(std::size_t, std::vector<std::uint8_t>&, const std::string&) {}
void GzipReader::expect_end(const std::string&) {}
std::vector<std::uint8_t> gzip_peek(const unsigned char*, std::size_t, std::size_t, bool* corrupt) {
  if (corrupt) *corrupt = false;
  return {};
}
bool have_gzip_support() { return false; }

#endif

#ifdef FLASHGS_HAVE_ZSTD

constexpr int kMaxZstdWindowLog = 27;
constexpr int kMaxZstdWindowMegabytes = (1 << kMaxZstdWindowLog) >> 20;

std::vector<std::uint8_t> zstd_decompress_exact(const unsigned char* data, std::size_t size, std::size_t expected,
                                                const std::string& name, const std::string& what,
                                                LoadProgress* progress) {
  std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> context(ZSTD_createDCtx(), ZSTD_freeDCtx);
  if (!context) fail(name, "cannot start the zstd decoder");
  // A window beyond 128 MB is not a splat attribute stream; it would only cost memory.
  ZSTD_DCtx_setParameter(context.get(), ZSTD_d_windowLogMax, kMaxZstdWindowLog);
  std::vector<std::uint8_t> out;
  ZSTD_inBuffer in{data, size, 0};
  std::size_t pending = 1;  // ZSTD_decompressStream's "more to do" hint; 0 once the frame is complete
  while (pending != 0) {
    const std::size_t before = out.size();
    // One byte of room past `expected`, so a frame holding more is seen rather than truncated.
    const std::size_t step = std::min(kGrowStep, expected + 1 - before);
    out.resize(before + step);
    ZSTD_outBuffer buffer{out.data() + before, step, 0};
    const std::size_t in_before = in.pos;
    pending = ZSTD_decompressStream(context.get(), &buffer, &in);
    out.resize(before + buffer.pos);
    if (ZSTD_isError(pending) && ZSTD_getErrorCode(pending) == ZSTD_error_frameParameter_windowTooLarge)
      fail(name, "the zstd frame of the " + what + " asks for a decoding window larger than the " +
                     std::to_string(kMaxZstdWindowMegabytes) + " MB allowed here: too large for a splat stream");
    if (ZSTD_isError(pending))
      fail(name, "the zstd data of the " + what + " is corrupt (" + ZSTD_getErrorName(pending) + ")");
    add_progress(progress, in.pos - in_before, name);
    if (out.size() > expected)
      fail(name, "the " + what + " stream holds more than the " + std::to_string(expected) +
                     " bytes the header declares (a wrong count, or a zstd bomb)");
    if (pending != 0 && in.pos == size && buffer.pos < buffer.size)
      fail(name, "the zstd stream of the " + what + " is cut short (truncated file)");
  }
  if (out.size() != expected)
    fail(name, "the " + what + " stream holds " + std::to_string(out.size()) + " bytes, the header declares " +
                   std::to_string(expected));
  if (in.pos != size)
    fail(name, "the " + what + " stream has " + std::to_string(size - in.pos) + " bytes after its zstd frame");
  return out;
}

bool have_zstd_support() { return true; }

#else

std::vector<std::uint8_t> zstd_decompress_exact(const unsigned char*, std::size_t, std::size_t, const std::string& name,
                                                const std::string&, LoadProgress*) {
  fail(name, "this build has no zstd, so SPZ version 4 cannot be read (install libzstd-dev and rebuild)");
}
bool have_zstd_support() { return false; }

#endif

}  // namespace flashgs
