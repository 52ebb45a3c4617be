// Reads .ksplat files (GaussianSplats3D): a 4096-byte header, 1024-byte section headers, then
// per section its bucket table and its Gaussians in one of three compression modes (floats;
// halves with 16-bit positions about bucket centres; the same with 8-bit SH). Every count and
// offset is checked against the file before it is used.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/model_constants.h"
#include "format_readers.h"

namespace flashgs {
namespace {

constexpr std::size_t kMainHeaderBytes = 4096, kSectionHeaderBytes = 1024;
// SH values per Gaussian for degrees 0-3 (3 channels).
constexpr int kShValues[4] = {0, 9, 24, 45};
constexpr std::uint32_t kMaxSections = 1u << 20;

[[noreturn]] void fail(const std::string& name, const std::string& problem) { throw Error(name + ": " + problem); }

std::uint16_t u16(const unsigned char* p) { return static_cast<std::uint16_t>(p[0] | p[1] << 8); }
std::uint32_t u32(const unsigned char* p) { return std::uint32_t{u16(p)} | std::uint32_t{u16(p + 2)} << 16; }
float f32(const unsigned char* p) {
  float v;
  std::memcpy(&v, p, 4);  // little endian, as the format and every host we build for
  return v;
}
double f16(const unsigned char* p) {
  const std::uint16_t h = u16(p);
  const int exponent = (h >> 10) & 0x1f, mantissa = h & 0x3ff;
  const double sign = (h & 0x8000) ? -1.0 : 1.0;
  if (exponent == 0) return sign * std::ldexp(mantissa, -24);
  if (exponent == 31) return mantissa ? NAN : sign * INFINITY;
  return sign * std::ldexp(mantissa + 1024, exponent - 25);
}

// Bytes of each part of a Gaussian in compression mode 0 (floats) or 1-2 (halves).
struct Layout {
  int mode;
  std::size_t centre, scale, rotation, colour = 4, sh_value;
  explicit Layout(int m)
      : mode(m), centre(m == 0 ? 12 : 6), scale(m == 0 ? 12 : 6), rotation(m == 0 ? 16 : 8),
        sh_value(m == 0 ? 4 : m == 1 ? 2 : 1) {}
  std::size_t bytes(int sh_degree) const { return centre + scale + rotation + colour + kShValues[sh_degree] * sh_value; }
  double value(const unsigned char* p) const { return mode == 0 ? f32(p) : f16(p); }
};

struct Section {
  std::uint32_t count, capacity, bucket_capacity, buckets, full_buckets, partial_buckets, quantisation;
  float block_size;
  std::uint16_t bucket_bytes;
  int sh_degree;
};

Section read_section_header(const unsigned char* h, int mode, std::size_t index, const std::string& name) {
  Section s;
  s.count = u32(h);
  s.capacity = u32(h + 4);
  s.bucket_capacity = u32(h + 8);
  s.buckets = u32(h + 12);
  s.block_size = f32(h + 16);
  s.bucket_bytes = u16(h + 20);
  s.quantisation = u32(h + 24);
  if (s.quantisation == 0) s.quantisation = mode == 0 ? 1 : 32767;
  s.full_buckets = u32(h + 32);
  s.partial_buckets = u32(h + 36);
  s.sh_degree = u16(h + 40);
  const std::string where = "section " + std::to_string(index) + ": ";
  if (s.sh_degree > 3) fail(name, where + "SH degree " + std::to_string(s.sh_degree) + " (0-3 exist)");
  if (s.count > s.capacity)
    fail(name, where + std::to_string(s.count) + " Gaussians in room for " + std::to_string(s.capacity));
  if (mode != 0 && s.count > 0) {
    if (std::uint64_t{s.full_buckets} + s.partial_buckets > s.buckets)
      fail(name, where + "more full and partial buckets than the " + std::to_string(s.buckets) + " it has");
    if (std::uint64_t{s.full_buckets} * s.bucket_capacity > s.count)
      fail(name, where + "its full buckets hold more than its " + std::to_string(s.count) + " Gaussians");
    if (s.bucket_bytes < 12) fail(name, where + "a bucket record of " + std::to_string(s.bucket_bytes) + " bytes (a centre needs 12)");
    if (!std::isfinite(s.block_size)) fail(name, where + "the block size is not finite");
  }
  return s;
}

}  // namespace

Scene parse_ksplat(const char* data, std::size_t size, const std::string& name, LoadReport& report,
                   LoadProgress* progress) {
  report = LoadReport{};
  report.path = name;
  const auto* bytes = reinterpret_cast<const unsigned char*>(data);
  if (size < kMainHeaderBytes)
    fail(name, "a .ksplat file starts with a 4096-byte header, but the file has " + std::to_string(size) + " bytes");
  if (bytes[0] != 0 || bytes[1] < 1)
    fail(name, ".ksplat version " + std::to_string(bytes[0]) + "." + std::to_string(bytes[1]) +
                   " is not supported (0.1 and later 0.x are)");
  const std::uint32_t sections = u32(bytes + 4);
  const std::uint32_t total = u32(bytes + 16);
  const int mode = u16(bytes + 20);
  if (mode > 2) fail(name, "compression mode " + std::to_string(mode) + " (0, 1 and 2 exist)");
  if (total == 0) fail(name, "the header declares 0 Gaussians");
  if (sections > kMaxSections || sections > (size - kMainHeaderBytes) / kSectionHeaderBytes)
    fail(name, "the header declares " + std::to_string(sections) + " sections but the file cannot hold their headers");
  float sh_min = f32(bytes + 36), sh_max = f32(bytes + 40);
  if (sh_min == 0.0f) sh_min = -1.5f;  // the format's defaults when left zero
  if (sh_max == 0.0f) sh_max = 1.5f;
  const Layout layout(mode);

  std::vector<Section> section;
  int degree = 0;
  std::uint64_t declared = 0;
  for (std::uint32_t s = 0; s < sections; ++s) {
    section.push_back(read_section_header(bytes + kMainHeaderBytes + s * kSectionHeaderBytes, mode, s, name));
    if (section.back().count > 0) degree = std::max(degree, section.back().sh_degree);
    declared += section.back().count;
  }
  if (declared != total)
    fail(name, "the sections hold " + std::to_string(declared) + " Gaussians but the header declares " +
                   std::to_string(total));
  report.vertices_in_file = total;
  report.sh_degree_in_file = degree;

  Scene scene;
  scene.sh_degree = degree;
  scene.reserve(total);
  std::vector<float> rest(static_cast<std::size_t>(scene.sh_rest_per_gaussian()));
  DecodeProgress decoding(progress, name, total);
  std::uint64_t offset = kMainHeaderBytes + std::uint64_t{sections} * kSectionHeaderBytes;
  std::size_t done = 0;
  for (std::uint32_t s = 0; s < sections; ++s) {
    const Section& sec = section[s];
    const std::string where = "section " + std::to_string(s) + ": ";
    const std::uint64_t partial_bytes = std::uint64_t{sec.partial_buckets} * 4;
    const std::uint64_t bucket_bytes = std::uint64_t{sec.bucket_bytes} * sec.buckets + partial_bytes;
    const std::size_t per_gaussian = layout.bytes(sec.sh_degree);
    const std::uint64_t data_bytes = std::uint64_t{per_gaussian} * sec.capacity;
    if (offset > size || bucket_bytes > size - offset || data_bytes > size - offset - bucket_bytes)
      fail(name, where + "its buckets and Gaussians run past the end of the " + std::to_string(size) +
                     "-byte file: truncated file or wrong counts");
    const unsigned char* partial_sizes = bytes + offset;
    const unsigned char* centres = bytes + offset + partial_bytes;
    const unsigned char* gaussians = bytes + offset + bucket_bytes;
    const double position_scale = sec.block_size / 2.0 / sec.quantisation;
    const std::size_t full_gaussians = std::size_t{sec.full_buckets} * sec.bucket_capacity;
    std::size_t bucket = 0, partial = 0, partial_end = full_gaussians;
    for (std::size_t i = 0; i < sec.count; ++i) {
      decoding.at(done++);
      const unsigned char* g = gaussians + i * per_gaussian;
      DecodedGaussian d;
      if (mode == 0) {
        for (int k = 0; k < 3; ++k) d.position[k] = f32(g + 4 * k);
      } else {
        if (i < full_gaussians) {
          bucket = i / sec.bucket_capacity;
        } else {
          while (i >= partial_end) {  // the next partial bucket
            if (partial >= sec.partial_buckets)
              fail(name, where + "Gaussian " + std::to_string(i) + " lies past its last partial bucket");
            bucket = sec.full_buckets + partial;
            partial_end += u32(partial_sizes + 4 * partial++);
          }
        }
        const unsigned char* centre = centres + bucket * sec.bucket_bytes;
        for (int k = 0; k < 3; ++k)
          d.position[k] = (double(u16(g + 2 * k)) - sec.quantisation) * position_scale + f32(centre + 4 * k);
      }
      const unsigned char* scale = g + layout.centre;
      const unsigned char* rotation = scale + layout.scale;
      const unsigned char* colour = rotation + layout.rotation;
      const unsigned char* sh = colour + layout.colour;
      const std::size_t step = mode == 0 ? 4 : 2;
      for (int k = 0; k < 3; ++k) {
        d.scale[k] = layout.value(scale + step * k);
        d.sh_dc[k] = (colour[k] / 255.0 - 0.5) / model::kShC0;
      }
      for (int k = 0; k < 4; ++k) d.rotation[k] = layout.value(rotation + step * k);
      d.opacity = colour[3] / 255.0;
      // Band by band, channel-major inside each band; the scene keeps [coefficient][channel].
      std::fill(rest.begin(), rest.end(), 0.0f);
      const int first_coefficient[3] = {0, 3, 8}, band_size[3] = {3, 5, 7};
      for (int v = 0, band = 0; band < sec.sh_degree; ++band)
        for (int channel = 0; channel < 3; ++channel)
          for (int c = 0; c < band_size[band]; ++c, ++v) {
            const double value = mode == 2 ? sh_min + (sh_max - sh_min) * sh[v] / 255.0 : layout.value(sh + layout.sh_value * v);
            rest[static_cast<std::size_t>((first_coefficient[band] + c) * 3 + channel)] = static_cast<float>(value);
          }
      append_gaussian(scene, d, rest.data(), report);
    }
    offset += bucket_bytes + data_bytes;
  }
  decoding.done(total);
  if (scene.size() == 0) fail(name, "all " + std::to_string(total) + " Gaussians have NaN or Inf values");
  return scene;
}

}  // namespace flashgs
