// Reads Niantic SPZ files: versions 1-3 are one gzip stream (16-byte header, then each
// attribute for every Gaussian in turn), version 4 a 32-byte header, a table of contents and
// one zstd frame per attribute. Every size is checked against the header's count before use.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "compressed_streams.h"
#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/frame_memory.h"
#include "format_readers.h"
#include "kernel_marks.h"
#include "spz_axes.h"

namespace flashgs {
namespace {

constexpr std::uint32_t kSpzMagic = 0x5053474e;  // "NGSP", little endian
constexpr int kMaxVersion = 4;
constexpr std::size_t kGzipHeaderBytes = 16, kV4HeaderBytes = 32, kTocEntryBytes = 16;
constexpr std::uint8_t kFlagHasExtensions = 0x2;
// The format's fixed quantisation (SPZ's packer): colour = 0.5 + 0.15 f_dc in a byte, log
// scale = byte / 16 - 10, SH = (byte - 128) / 128.
constexpr double kColorScale = 0.15;
// Deflate expands at most about 1032:1; a count needing more than that is a lie.
constexpr std::uint64_t kMaxDeflateRatio = 1032;
// Progress is published and cancellation checked every this many Gaussians.
constexpr std::size_t kProgressStep = 1 << 16;

[[noreturn]] void fail(const std::string& name, const std::string& problem) { throw Error(name + ": " + problem); }

std::uint32_t read_u32(const unsigned char* p) {
  return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 | std::uint32_t{p[3]} << 24;
}
std::uint64_t read_u64(const unsigned char* p) { return std::uint64_t{read_u32(p)} | std::uint64_t{read_u32(p + 4)} << 32; }

// SH coefficients per channel beyond the DC term, for a degree (SPZ allows 0..4).
int sh_rest_dim(int degree) { return (degree + 1) * (degree + 1) - 1; }

struct Header {
  std::uint32_t version = 0;
  std::uint32_t count = 0;
  int sh_degree = 0;
  int fractional_bits = 0;
  std::uint8_t flags = 0;
};

// Bytes per Gaussian of each attribute, in file order.
struct Layout {
  std::size_t position, alpha = 1, color = 3, scale = 3, rotation, sh;
  explicit Layout(const Header& h)
      : position(h.version == 1 ? 6 : 9), rotation(h.version >= 3 ? 4 : 3),
        sh(static_cast<std::size_t>(sh_rest_dim(h.sh_degree)) * 3) {}
  std::size_t total() const { return position + alpha + color + scale + rotation + sh; }
};

const char* const kAttributeNames[] = {"positions", "alphas", "colours", "scales", "rotations",
                                       "spherical harmonics"};

struct Packed {
  std::vector<std::uint8_t> attribute[6];  // in kAttributeNames order
};

Header parse_header(const unsigned char* h, const std::string& name) {
  Header header;
  if (read_u32(h) != kSpzMagic) fail(name, "not an SPZ file (no \"NGSP\" magic)");
  header.version = read_u32(h + 4);
  header.count = read_u32(h + 8);
  header.sh_degree = h[12];
  header.fractional_bits = h[13];
  header.flags = h[14];
  if (header.version < 1 || header.version > kMaxVersion)
    fail(name, "SPZ version " + std::to_string(header.version) + " is not supported (versions 1-4 are)");
  if (header.count == 0) fail(name, "the header declares 0 Gaussians");
  if (header.sh_degree > 4) fail(name, "the header declares SH degree " + std::to_string(header.sh_degree) + " (0-4 exist)");
  if (header.fractional_bits > 24)
    fail(name, "the header declares " + std::to_string(header.fractional_bits) +
                   " fractional bits for 24-bit positions (at most 24)");
  return header;
}

// Refuses a count whose decoded scene cannot fit in memory, before any of it is allocated.
void check_memory(const Header& header, const Layout& layout, const std::string& name) {
  const int kept_degree = std::min(header.sh_degree, 3);
  const std::uint64_t scene_bytes = sizeof(float) * (14 + 3 * static_cast<std::uint64_t>(sh_rest_dim(kept_degree)));
  const std::uint64_t need = header.count * (scene_bytes + layout.total());
  const AvailableMemory available = available_host_memory();
  if (available.bytes > 0 && need > available.bytes)
    fail(name, "the header declares " + std::to_string(header.count) + " Gaussians, " + format_bytes(need) +
                   " once decoded, but only " + format_bytes(available.bytes) + " of memory is available");
}

Packed read_gzip_streams(const unsigned char* data, std::size_t size, Header& header, const std::string& name,
                         LoadProgress* progress) {
  GzipReader reader(data, size, name, progress);
  std::vector<std::uint8_t> head;
  reader.read(kGzipHeaderBytes, head, "header");
  header = parse_header(head.data(), name);
  if (header.version == 4) fail(name, "an SPZ version 4 header inside a gzip stream (version 4 is not gzipped)");
  const Layout layout(header);
  const std::uint64_t expected = std::uint64_t{header.count} * layout.total();
  if (expected > size * kMaxDeflateRatio)
    fail(name, "the header declares " + std::to_string(header.count) + " Gaussians (" + std::to_string(expected) +
                   " bytes) but " + std::to_string(size) + " compressed bytes cannot hold that much: a wrong count");
  check_memory(header, layout, name);
  Packed packed;
  const std::size_t sizes[6] = {layout.position, layout.alpha, layout.color, layout.scale, layout.rotation, layout.sh};
  for (int a = 0; a < 6; ++a) {
    packed.attribute[a].reserve(header.count * sizes[a]);
    reader.read(header.count * sizes[a], packed.attribute[a], kAttributeNames[a]);
  }
  // Extensions (vendor records) follow the Gaussians; they are not read.
  if (!(header.flags & kFlagHasExtensions))
    reader.expect_end(std::to_string(kGzipHeaderBytes + expected) + " bytes");
  return packed;
}

Packed read_zstd_streams(const unsigned char* data, std::size_t size, Header& header, const std::string& name,
                         LoadProgress* progress) {
  if (size < kV4HeaderBytes) fail(name, "the SPZ version 4 header is cut short (" + std::to_string(size) + " bytes)");
  header = parse_header(data, name);
  if (header.version != 4) fail(name, "an SPZ header of version " + std::to_string(header.version) + " here");
  const Layout layout(header);
  const int streams = data[15];
  const std::uint32_t toc_offset = read_u32(data + 16);
  const int needed = header.sh_degree > 0 ? 6 : 5;
  if (streams < needed || (streams > needed && !(header.flags & kFlagHasExtensions)))
    fail(name, "the header declares " + std::to_string(streams) + " streams; SH degree " +
                   std::to_string(header.sh_degree) + " needs " + std::to_string(needed));
  if (toc_offset < kV4HeaderBytes || toc_offset > size || (size - toc_offset) / kTocEntryBytes < std::size_t(streams))
    fail(name, "the table of contents (at byte " + std::to_string(toc_offset) + ", " + std::to_string(streams) +
                   " entries) lies outside the " + std::to_string(size) + "-byte file");
  check_memory(header, layout, name);
  const std::size_t sizes[6] = {layout.position, layout.alpha, layout.color, layout.scale, layout.rotation, layout.sh};
  std::uint64_t offset = toc_offset + std::uint64_t(streams) * kTocEntryBytes;
  Packed packed;
  for (int s = 0; s < streams; ++s) {
    const unsigned char* entry = data + toc_offset + s * kTocEntryBytes;
    const std::uint64_t compressed = read_u64(entry), uncompressed = read_u64(entry + 8);
    const std::string what = s < needed ? kAttributeNames[s] : "extension " + std::to_string(s - needed);
    if (compressed > size - offset)
      fail(name, "the " + what + " stream (" + std::to_string(compressed) + " bytes at byte " + std::to_string(offset) +
                     ") runs past the end of the " + std::to_string(size) + "-byte file: truncated file");
    if (s < needed) {
      const std::uint64_t expected = std::uint64_t{header.count} * sizes[s];
      if (uncompressed != expected)
        fail(name, "the " + what + " stream declares " + std::to_string(uncompressed) + " bytes; " +
                       std::to_string(header.count) + " Gaussians need " + std::to_string(expected));
      packed.attribute[s] = zstd_decompress_exact(data + offset, compressed, expected, name, what, progress);
    }
    offset += compressed;
  }
  if (offset != size)
    fail(name, "the streams end at byte " + std::to_string(offset) + " but the file has " + std::to_string(size) +
                   " bytes: a wrong table of contents, or junk after it");
  return packed;
}

// Versions 1-3 stored without gzip (some writers leave the stream uncompressed): the 16-byte
// header, then each attribute in turn, exactly as inside the gzip stream.
Packed read_raw_streams(const unsigned char* data, std::size_t size, Header& header, const std::string& name) {
  if (size < kGzipHeaderBytes) fail(name, "the SPZ header is cut short (" + std::to_string(size) + " bytes)");
  header = parse_header(data, name);
  const Layout layout(header);
  const std::uint64_t expected = std::uint64_t{header.count} * layout.total();
  const std::uint64_t available = size - kGzipHeaderBytes;
  if (expected > available || (expected < available && !(header.flags & kFlagHasExtensions)))
    fail(name, "the header declares " + std::to_string(header.count) + " Gaussians (" + std::to_string(expected) +
                   " bytes) but the uncompressed file holds " + std::to_string(available) + " bytes after it: " +
                   (expected > available ? "truncated file or wrong count" : "extra data or wrong count"));
  check_memory(header, layout, name);
  Packed packed;
  const std::size_t sizes[6] = {layout.position, layout.alpha, layout.color, layout.scale, layout.rotation, layout.sh};
  const unsigned char* at = data + kGzipHeaderBytes;
  for (int a = 0; a < 6; ++a) {
    packed.attribute[a].assign(at, at + header.count * sizes[a]);
    at += header.count * sizes[a];
  }
  return packed;
}

float half_to_float(std::uint16_t h) {
  const int exponent = (h >> 10) & 0x1f, mantissa = h & 0x3ff;
  const double sign = (h & 0x8000) ? -1.0 : 1.0;
  if (exponent == 0) return static_cast<float>(sign * std::ldexp(mantissa, -24));
  if (exponent == 31) return mantissa ? NAN : static_cast<float>(sign * INFINITY);
  return static_cast<float>(sign * std::ldexp(mantissa + 1024, exponent - 25));
}

// Version 3+: the largest component's index in the top 2 bits, then three 10-bit fields (a
// sign bit and 9 bits of magnitude in [0, 1/sqrt 2]), the last component in the lowest bits.
void unpack_smallest_three(const std::uint8_t* r, double q[4]) {
  std::uint32_t bits = read_u32(r);
  const int largest = static_cast<int>(bits >> 30);
  double sum = 0;
  for (int i = 3; i >= 0; --i) {
    if (i == largest) continue;
    const double magnitude = (bits & 511u) / 511.0 * std::sqrt(0.5);
    q[i] = (bits >> 9) & 1u ? -magnitude : magnitude;
    sum += q[i] * q[i];
    bits >>= 10;
  }
  q[largest] = std::sqrt(std::max(0.0, 1.0 - sum));
}

// Turns the attribute bytes into the scene's activated floats in PLY axes (quaternions are
// stored x y z w).
Scene unpack(const Packed& packed, const Header& header, const std::string& name, LoadReport* report,
             LoadProgress* progress, SpzAxes axes) {
  const std::size_t n = header.count;
  const int degree = std::min(header.sh_degree, 3);
  const int file_dim = sh_rest_dim(header.sh_degree), kept_dim = sh_rest_dim(degree);
  const double position_scale = std::ldexp(1.0, -header.fractional_bits);
  Scene scene;
  scene.sh_degree = degree;
  scene.trained_kernel = kernel_from_spz_flags(header.flags);
  scene.reserve(n);
  if (progress) progress->gaussians_total.store(n, std::memory_order_relaxed);
  const auto& pos = packed.attribute[0];
  const auto& alpha = packed.attribute[1];
  const auto& color = packed.attribute[2];
  const auto& scale = packed.attribute[3];
  const auto& rot = packed.attribute[4];
  const auto& sh = packed.attribute[5];
  for (std::size_t i = 0; i < n; ++i) {
    if (progress && i % kProgressStep == 0) {
      progress->gaussians_done.store(i, std::memory_order_relaxed);
      if (progress->cancel_requested.load(std::memory_order_relaxed)) throw LoadCancelled(name);
    }
    float p[3];
    for (int k = 0; k < 3; ++k) {
      if (header.version == 1) {
        const std::uint8_t* b = &pos[i * 6 + k * 2];
        p[k] = half_to_float(static_cast<std::uint16_t>(b[0] | b[1] << 8));
      } else {
        const std::uint8_t* b = &pos[i * 9 + k * 3];
        std::int32_t fixed = b[0] | b[1] << 8 | b[2] << 16;
        if (fixed & 0x800000) fixed -= 1 << 24;  // 24-bit two's complement
        p[k] = static_cast<float>(fixed * position_scale);
      }
    }
    if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) {  // only half floats can be
      report->dropped_non_finite++;
      continue;
    }
    double q[4];  // x y z w
    if (header.version >= 3) {
      unpack_smallest_three(&rot[i * 4], q);
    } else {
      double sum = 0;
      for (int k = 0; k < 3; ++k) {
        q[k] = rot[i * 3 + k] / 127.5 - 1.0;
        sum += q[k] * q[k];
      }
      q[3] = std::sqrt(std::max(0.0, 1.0 - sum));
    }
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int k = 0; k < 3; ++k) scene.positions.push_back(spz_axis_sign(axes, k) * p[k]);
    for (int k = 0; k < 3; ++k) scene.scales.push_back(static_cast<float>(std::exp(scale[i * 3 + k] / 16.0 - 10.0)));
    scene.rotations.push_back(static_cast<float>(q[3] / norm));
    for (int k = 0; k < 3; ++k) scene.rotations.push_back(spz_axis_sign(axes, k) * static_cast<float>(q[k] / norm));
    scene.opacities.push_back(static_cast<float>(alpha[i] / 255.0));
    for (int k = 0; k < 3; ++k)
      scene.sh_dc.push_back(static_cast<float>((color[i * 3 + k] / 255.0 - 0.5) / kColorScale));
    // [coefficient][channel] in the file as in the scene; degree 4's band is left out.
    const std::uint8_t* coefficients = sh.empty() ? nullptr : &sh[i * file_dim * 3];
    for (int c = 0; c < kept_dim * 3; ++c)
      scene.sh_rest.push_back(spz_sh_sign(axes, c / 3) * static_cast<float>((coefficients[c] - 128.0) / 128.0));
  }
  if (progress) progress->gaussians_done.store(n, std::memory_order_relaxed);
  if (scene.size() == 0) fail(name, "all " + std::to_string(n) + " Gaussians have non-finite positions");
  return scene;
}

}  // namespace

DeclaredScene declare_spz(const char* start, std::size_t start_size, const std::string& name) {
  const auto* bytes = reinterpret_cast<const unsigned char*>(start);
  std::vector<std::uint8_t> head;
  if (start_size >= 2 && bytes[0] == 0x1f && bytes[1] == 0x8b)
    head = gzip_peek(bytes, start_size, kGzipHeaderBytes);
  else
    head.assign(bytes, bytes + std::min(start_size, kV4HeaderBytes));
  if (head.size() < kGzipHeaderBytes) return {};  // the reader says what is wrong
  const Header header = parse_header(head.data(), name);
  DeclaredScene declared;
  declared.gaussians = header.count;
  declared.sh_degree = std::min(header.sh_degree, 3);
  declared.extra_bytes_per_gaussian = Layout(header).total();
  return declared;
}

bool looks_like_spz(const char* data, std::size_t size) {
  const auto* bytes = reinterpret_cast<const unsigned char*>(data);
  if (size >= 2 && bytes[0] == 0x1f && bytes[1] == 0x8b) {
    // Any gzip file starts so: the SPZ magic must open the stream as well. Without zlib a
    // gzip file is taken for SPZ, whose reader then says zlib is missing.
    if (!have_gzip_support()) return true;
    // A corrupt stream is taken for SPZ too, so that its reader says "corrupt gzip" rather
    // than the file being no scene at all.
    bool corrupt = false;
    const std::vector<std::uint8_t> start = gzip_peek(bytes, size, 4, &corrupt);
    return corrupt || (start.size() == 4 && read_u32(start.data()) == kSpzMagic);
  }
  return size >= 8 && read_u32(bytes) == kSpzMagic;
}

Scene parse_spz(const char* data, std::size_t size, const std::string& name, LoadReport* report,
                LoadProgress* progress, SpzAxes axes) {
  LoadReport local_report;
  if (!report) report = &local_report;
  *report = LoadReport{};
  report->path = name;
  if (progress) {  // the compressed bytes as they are decompressed
    progress->bytes_done.store(0, std::memory_order_relaxed);
    progress->bytes_total.store(size, std::memory_order_relaxed);
  }
  const auto* bytes = reinterpret_cast<const unsigned char*>(data);
  if (size == 0) fail(name, "not an SPZ file (it is empty)");
  Header header;
  Packed packed;
  if (size >= 2 && bytes[0] == 0x1f && bytes[1] == 0x8b)
    packed = read_gzip_streams(bytes, size, header, name, progress);
  else if (size >= 8 && read_u32(bytes) == kSpzMagic && read_u32(bytes + 4) != 4)
    packed = read_raw_streams(bytes, size, header, name);
  else if (size >= 4 && read_u32(bytes) == kSpzMagic)
    packed = read_zstd_streams(bytes, size, header, name, progress);
  else
    fail(name, "not an SPZ file (neither a gzip stream nor the \"NGSP\" magic)");
  report->vertices_in_file = header.count;
  report->sh_degree_in_file = header.sh_degree;
  return unpack(packed, header, name, report, progress, axes);
}

Scene read_spz(const std::string& path, LoadReport* report, LoadProgress* progress, SpzAxes axes) {
  const std::vector<char> bytes = read_regular_file(path);
  return parse_spz(bytes.data(), bytes.size(), path, report, progress, axes);
}

}  // namespace flashgs
