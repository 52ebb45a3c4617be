// Builds small PlayCanvas compressed PLY and .splat files in memory for the format tests.
#pragma once

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

}  // namespace flashgs::test
