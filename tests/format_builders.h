// Builds small PlayCanvas compressed PLY, .splat and .ksplat files in memory for the format tests.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace flashgs::test {

inline void append_bytes(std::string& out, const void* data, std::size_t size) {
  out.append(static_cast<const char*>(data), size);
}

// A compressed PLY of `n` Gaussians with plausible packed words (SH degree `sh_degree`, 0-3,
// and the per-chunk colour bounds when `chunk_colours`). `declared_vertices` / `declared_chunks`
// >= 0 replace the counts in the header (for lying headers).
inline std::string compressed_ply_bytes(int n, int sh_degree = 0, bool chunk_colours = true,
                                        long long declared_vertices = -1, long long declared_chunks = -1) {
  const int chunks = (n + 255) / 256;
  const int sh_values = ((sh_degree + 1) * (sh_degree + 1) - 1) * 3;
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment built by the flashgs tests\n";
  out += "element chunk " + std::to_string(declared_chunks >= 0 ? declared_chunks : chunks) + "\n";
  const char* bounds[] = {"min_x", "min_y", "min_z", "max_x", "max_y", "max_z", "min_scale_x", "min_scale_y",
                          "min_scale_z", "max_scale_x", "max_scale_y", "max_scale_z", "min_r", "min_g", "min_b",
                          "max_r", "max_g", "max_b"};
  const int n_bounds = chunk_colours ? 18 : 12;
  for (int k = 0; k < n_bounds; ++k) out += std::string("property float ") + bounds[k] + "\n";
  out += "element vertex " + std::to_string(declared_vertices >= 0 ? declared_vertices : n) + "\n";
  for (const char* p : {"packed_position", "packed_rotation", "packed_scale", "packed_color"})
    out += std::string("property uint ") + p + "\n";
  if (sh_degree > 0) {
    out += "element sh " + std::to_string(n) + "\n";
    for (int k = 0; k < sh_values; ++k) out += "property uchar f_rest_" + std::to_string(k) + "\n";
  }
  out += "end_header\n";
  for (int c = 0; c < chunks; ++c) {
    const float lo[18] = {-1.0f - c, -1, 2, 1.0f + c, 1, 4, -5, -5, -5, -2, -2, -2, 0, 0, 0, 1, 1, 1};
    append_bytes(out, lo, 4u * static_cast<unsigned>(n_bounds));
  }
  for (int i = 0; i < n; ++i) {
    const std::uint32_t words[4] = {
        static_cast<std::uint32_t>(i * 2654435761u),               // position: any bits
        (512u << 20) | (512u << 10) | 512u,                       // rotation: about identity (w largest)
        static_cast<std::uint32_t>((i * 40503u) ^ 0x5a5a5a5au),   // scale
        static_cast<std::uint32_t>(i * 97u) | 0xc0u};              // colour, opacity >= 0.75
    append_bytes(out, words, sizeof words);
  }
  for (int i = 0; i < n && sh_degree > 0; ++i)
    for (int k = 0; k < sh_values; ++k) out.push_back(static_cast<char>((i + 7 * k) & 0xff));
  return out;
}

// One .splat record (32 bytes): float position and scale, RGBA and quaternion bytes (w x y z).
inline std::string splat_record(const float position[3], const float scale[3], const std::uint8_t rgba[4],
                                const std::uint8_t quat[4]) {
  std::string out;
  append_bytes(out, position, 12);
  append_bytes(out, scale, 12);
  append_bytes(out, rgba, 4);
  append_bytes(out, quat, 4);
  return out;
}

// ---- .ksplat ----

inline void put16(std::string& s, std::uint16_t v) { append_bytes(s, &v, 2); }
inline void put32(std::string& s, std::uint32_t v) { append_bytes(s, &v, 4); }
inline void putf(std::string& s, float v) { append_bytes(s, &v, 4); }
// The nearest half of a normal value.
inline std::uint16_t half_of(float v) {
  if (v == 0) return 0;
  const std::uint16_t sign = v < 0 ? 0x8000 : 0;
  int exponent;
  const float fraction = std::frexp(std::abs(v), &exponent);  // in [0.5, 1)
  int mantissa = static_cast<int>(std::lround((fraction * 2 - 1) * 1024));
  if (mantissa == 1024) mantissa = 0, ++exponent;  // rounded up to the next power of two
  return static_cast<std::uint16_t>(sign | (exponent - 1 + 15) << 10 | mantissa);
}

struct KsplatGaussian {
  float position[3], scale[3], rotation[4];
  std::uint8_t rgba[4];
  std::vector<float> sh;  // file order: band by band, channel-major in each band
};

// One section of `gs` with buckets of 4 (full ones, then partial ones of the remainder in
// twos), SH degree `degree`, compression `mode`; SH range [-2, 2] for mode 2.
inline std::string ksplat_file(const std::vector<KsplatGaussian>& gs, int mode, int degree) {
  const std::uint32_t capacity = 4, n = static_cast<std::uint32_t>(gs.size());
  const std::uint32_t full = n / capacity, rest = n % capacity;
  std::vector<std::uint32_t> partial;
  for (std::uint32_t left = rest; left > 0; left -= std::min(left, 2u)) partial.push_back(std::min(left, 2u));
  const std::uint32_t buckets = full + static_cast<std::uint32_t>(partial.size());
  const float block = 2.0f;
  const std::uint32_t q = 32767;
  std::string f(4096, '\0');
  f[0] = 0;
  f[1] = 1;
  const std::uint32_t sections = 1;
  std::memcpy(&f[4], &sections, 4);
  std::memcpy(&f[16], &n, 4);
  const std::uint16_t m = static_cast<std::uint16_t>(mode);
  std::memcpy(&f[20], &m, 2);
  const float lo = -2, hi = 2;
  std::memcpy(&f[36], &lo, 4);
  std::memcpy(&f[40], &hi, 4);
  std::string section(1024, '\0');
  const std::uint32_t header[] = {n, n, capacity, buckets};
  std::memcpy(&section[0], header, sizeof header);
  std::memcpy(&section[16], &block, 4);
  const std::uint16_t bucket_bytes = 12;
  std::memcpy(&section[20], &bucket_bytes, 2);
  std::memcpy(&section[32], &full, 4);
  const std::uint32_t partial_count = static_cast<std::uint32_t>(partial.size());
  std::memcpy(&section[36], &partial_count, 4);
  const std::uint16_t d = static_cast<std::uint16_t>(degree);
  std::memcpy(&section[40], &d, 2);
  f += section;
  for (std::uint32_t p : partial) put32(f, p);
  // Bucket b's centre: (b, -b, 0.5 b).
  for (std::uint32_t b = 0; b < buckets; ++b) {
    putf(f, float(b));
    putf(f, -float(b));
    putf(f, 0.5f * b);
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    const KsplatGaussian& g = gs[i];
    const std::uint32_t bucket = i < full * capacity ? i / capacity : full + (i - full * capacity) / 2;
    const float centre[3] = {float(bucket), -float(bucket), 0.5f * bucket};
    auto value = [&](float v) { mode == 0 ? putf(f, v) : put16(f, half_of(v)); };
    for (int k = 0; k < 3; ++k) {
      if (mode == 0)
        putf(f, g.position[k]);
      else
        put16(f, static_cast<std::uint16_t>(std::lround((g.position[k] - centre[k]) / (block / 2 / q) + q)));
    }
    for (float s : g.scale) value(s);
    for (float r : g.rotation) value(r);
    f.append(reinterpret_cast<const char*>(g.rgba), 4);
    for (float v : g.sh) {
      if (mode == 2)
        f.push_back(static_cast<char>(std::lround((v - lo) / (hi - lo) * 255)));
      else
        value(v);
    }
  }
  return f;
}

}  // namespace flashgs::test
