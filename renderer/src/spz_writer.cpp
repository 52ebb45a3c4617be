// Writes Niantic SPZ, the inverse of spz_reader.cpp: version 3 (one gzip stream of a 16-byte
// header and each attribute in turn) or version 4 (a 32-byte header, a table of contents and
// one zstd frame per attribute); every value rounded to its nearest step.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/file_write.h"
#include "format_writers.h"
#include "kernel_marks.h"
#include "spz_axes.h"
#include "stream_compress.h"

namespace flashgs {
namespace {

constexpr std::uint32_t kSpzMagic = 0x5053474e;  // "NGSP", little endian
constexpr std::uint32_t kV4HeaderBytes = 32;
constexpr double kColorScale = 0.15;  // colour byte = (0.5 + 0.15 f_dc) * 255
// Positions are 24-bit two's complement fixed point.
constexpr double kMaxFixed = (1 << 23) - 1;
constexpr int kMaxFractionalBits = 24;

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
}
void put_u64(std::vector<std::uint8_t>& out, std::uint64_t v) {
  put_u32(out, static_cast<std::uint32_t>(v));
  put_u32(out, static_cast<std::uint32_t>(v >> 32));
}

std::uint8_t to_byte(double v) { return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0))); }

// The most fractional bits that keep every coordinate within 24 bits.
int fractional_bits_for(const Scene& scene, const std::string& path) {
  double largest = 0;
  for (float p : scene.positions) largest = std::max(largest, std::abs(static_cast<double>(p)));
  int bits = kMaxFractionalBits;
  while (bits >= 0 && std::round(largest * std::ldexp(1.0, bits)) > kMaxFixed) --bits;
  if (bits < 0)
    throw Error(path + ": a position of magnitude " + std::to_string(largest) +
                " does not fit SPZ's 24-bit fixed point (at most 8388607)");
  return bits;
}

// Version 3+: smallest-three of x y z w, the largest made positive and named in the top two
// bits, each other component as a sign bit and 9 bits of magnitude in [0, 1/sqrt 2], the
// last one in the lowest bits.
std::uint32_t pack_rotation(const double q[4]) {
  int largest = 0;
  for (int k = 1; k < 4; ++k)
    if (std::abs(q[k]) > std::abs(q[largest])) largest = k;
  const double sign = q[largest] < 0 ? -1.0 : 1.0;
  std::uint32_t word = static_cast<std::uint32_t>(largest);
  for (int k = 0; k < 4; ++k) {
    if (k == largest) continue;
    const double c = sign * q[k];
    const std::uint32_t magnitude = quantise_unit(std::abs(c) / std::sqrt(0.5), 9);
    word = word << 10 | (c < 0 ? 1u << 9 : 0u) | magnitude;
  }
  return word;
}

struct Attributes {
  std::vector<std::uint8_t> bytes[6];  // positions, alphas, colours, scales, rotations, SH
};

Attributes quantise(const Scene& scene, int fractional_bits, SpzAxes axes) {
  const std::size_t n = scene.size();
  const int rest = scene.sh_rest_per_gaussian();
  const double fixed_scale = std::ldexp(1.0, fractional_bits);
  Attributes a;
  a.bytes[0].reserve(n * 9);
  a.bytes[1].reserve(n);
  a.bytes[2].reserve(n * 3);
  a.bytes[3].reserve(n * 3);
  a.bytes[4].reserve(n * 4);
  a.bytes[5].reserve(n * rest);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      const double p = spz_axis_sign(axes, k) * scene.positions[i * 3 + k];
      const std::int32_t fixed = static_cast<std::int32_t>(std::lround(p * fixed_scale));
      for (int b = 0; b < 3; ++b) a.bytes[0].push_back(static_cast<std::uint8_t>(fixed >> (8 * b)));
    }
    a.bytes[1].push_back(to_byte(scene.opacities[i] * 255.0));
    for (int k = 0; k < 3; ++k) a.bytes[2].push_back(to_byte((0.5 + kColorScale * scene.sh_dc[i * 3 + k]) * 255.0));
    for (int k = 0; k < 3; ++k) a.bytes[3].push_back(to_byte((std::log(double(scene.scales[i * 3 + k])) + 10.0) * 16.0));
    const float* r = &scene.rotations[i * 4];  // w x y z
    const double q[4] = {spz_axis_sign(axes, 0) * r[1], spz_axis_sign(axes, 1) * r[2], spz_axis_sign(axes, 2) * r[3],
                         r[0]};
    const std::uint32_t word = pack_rotation(q);
    for (int b = 0; b < 4; ++b) a.bytes[4].push_back(static_cast<std::uint8_t>(word >> (8 * b)));
    for (int c = 0; c < rest; ++c)
      a.bytes[5].push_back(to_byte(spz_sh_sign(axes, c / 3) * scene.sh_rest[i * rest + c] * 128.0 + 128.0));
  }
  return a;
}

// magic, version, count, SH degree, fractional bits, flags (then version-specific bytes).
void put_common_header(std::vector<std::uint8_t>& out, int version, const Scene& scene, int fractional_bits) {
  put_u32(out, kSpzMagic);
  put_u32(out, static_cast<std::uint32_t>(version));
  put_u32(out, static_cast<std::uint32_t>(scene.size()));
  out.push_back(static_cast<std::uint8_t>(scene.sh_degree));
  out.push_back(static_cast<std::uint8_t>(fractional_bits));
  out.push_back(spz_flags_for(scene.trained_kernel));
}

std::vector<std::uint8_t> version3(const Scene& scene, const Attributes& a, int fractional_bits, const std::string& path) {
  std::vector<std::uint8_t> raw;
  put_common_header(raw, 3, scene, fractional_bits);
  raw.push_back(0);  // reserved
  for (const auto& attribute : a.bytes) raw.insert(raw.end(), attribute.begin(), attribute.end());
  return gzip_compress(raw.data(), raw.size(), path);
}

std::vector<std::uint8_t> version4(const Scene& scene, const Attributes& a, int fractional_bits, const std::string& path) {
  const int streams = scene.sh_degree > 0 ? 6 : 5;
  std::vector<std::uint8_t> out;
  put_common_header(out, 4, scene, fractional_bits);
  out.push_back(static_cast<std::uint8_t>(streams));
  put_u32(out, kV4HeaderBytes);  // the table of contents follows the header
  out.resize(kV4HeaderBytes, 0);
  std::vector<std::vector<std::uint8_t>> frames;
  for (int s = 0; s < streams; ++s) {
    frames.push_back(zstd_compress(a.bytes[s].data(), a.bytes[s].size(), path));
    put_u64(out, frames.back().size());
    put_u64(out, a.bytes[s].size());
  }
  for (const auto& frame : frames) out.insert(out.end(), frame.begin(), frame.end());
  return out;
}

}  // namespace

void save_spz(const Scene& scene, const std::string& path, const SceneWriteOptions& options) {
  if (options.spz_version != 3 && options.spz_version != 4)
    throw Error(path + ": SPZ version " + std::to_string(options.spz_version) + " cannot be written (3 or 4 can)");
  const int fractional_bits = fractional_bits_for(scene, path);
  const Attributes attributes = quantise(scene, fractional_bits, options.spz_axes);
  const std::vector<std::uint8_t> bytes = options.spz_version == 3
                                              ? version3(scene, attributes, fractional_bits, path)
                                              : version4(scene, attributes, fractional_bits, path);
  write_file_atomically(path, [&](OutputFile& file) { file.write(bytes.data(), bytes.size()); });
}

}  // namespace flashgs
