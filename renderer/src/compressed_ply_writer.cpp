// Writes PlayCanvas / SuperSplat compressed PLY: per 256 Gaussians a chunk of float min/max
// bounds (position, log-scale, colour), per Gaussian four packed words, and the SH bands as
// 8-bit values; the exact inverse of compressed_ply_reader.cpp, each field rounded to nearest.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <vector>

#include "flashgs/file_write.h"
#include "flashgs/model_constants.h"
#include "format_writers.h"
#include "kernel_marks.h"

namespace flashgs {
namespace {

constexpr std::size_t kChunkGaussians = 256;
constexpr int kChunkFloats = 18;
// Log-scales beyond this are clamped: a degenerate Gaussian must not stretch its chunk's range
// (the format's own writer clamps likewise).
constexpr double kMaxLogScale = 20.0;

double log_scale(const Scene& scene, std::size_t i, int k) {
  return std::clamp(std::log(static_cast<double>(scene.scales[i * 3 + k])), -kMaxLogScale, kMaxLogScale);
}

double colour(const Scene& scene, std::size_t i, int k) { return 0.5 + model::kShC0 * scene.sh_dc[i * 3 + k]; }

// min x y z, max x y z, min/max log-scale, min/max colour, for Gaussians [first, last).
void chunk_bounds(const Scene& scene, std::size_t first, std::size_t last, float bounds[kChunkFloats]) {
  for (int k = 0; k < 3; ++k) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t i = first; i < last; ++i) {
      const double v[3] = {scene.positions[i * 3 + k], log_scale(scene, i, k), colour(scene, i, k)};
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], v[a]);
        hi[a] = std::max(hi[a], v[a]);
      }
    }
    for (int a = 0; a < 3; ++a) {
      bounds[a * 6 + k] = static_cast<float>(lo[a]);
      bounds[a * 6 + 3 + k] = static_cast<float>(hi[a]);
    }
  }
}

std::uint32_t pack_11_10_11(const double v[3], const float* lo, const float* hi) {
  return quantise_range(v[0], lo[0], hi[0], 11) << 21 | quantise_range(v[1], lo[1], hi[1], 10) << 11 |
         quantise_range(v[2], lo[2], hi[2], 11);
}

// Smallest-three: the largest component (of w x y z) made positive and named in the top two
// bits, the other three in [-1/sqrt 2, 1/sqrt 2] as 10 bits each.
std::uint32_t pack_rotation(const float* q) {
  int largest = 0;
  for (int k = 1; k < 4; ++k)
    if (std::abs(q[k]) > std::abs(q[largest])) largest = k;
  const double sign = q[largest] < 0 ? -1.0 : 1.0;
  std::uint32_t word = static_cast<std::uint32_t>(largest);
  for (int k = 0; k < 4; ++k)
    if (k != largest) word = word << 10 | quantise_unit(sign * q[k] / std::sqrt(2.0) + 0.5, 10);
  return word;
}

// The reader maps byte v to (v + 0.5) / 256 (0 and 255 to the ends) times 8 minus 4.
std::uint8_t pack_sh(float value) {
  const double n = value / 8.0 + 0.5;
  return static_cast<std::uint8_t>(std::clamp(std::floor(n * 256.0), 0.0, 255.0));
}

std::string header_for(const Scene& scene, std::size_t chunks) {
  std::ostringstream h;
  h << "ply\nformat binary_little_endian 1.0\n";
  for (const std::string& comment : ply_comments_for(scene.trained_kernel)) h << "comment " << comment << "\n";
  h << "element chunk " << chunks << "\n";
  for (const char* p : {"min_x", "min_y", "min_z", "max_x", "max_y", "max_z", "min_scale_x", "min_scale_y",
                        "min_scale_z", "max_scale_x", "max_scale_y", "max_scale_z", "min_r", "min_g", "min_b", "max_r",
                        "max_g", "max_b"})
    h << "property float " << p << "\n";
  h << "element vertex " << scene.size() << "\n";
  for (const char* p : {"packed_position", "packed_rotation", "packed_scale", "packed_color"})
    h << "property uint " << p << "\n";
  const int rest = scene.sh_rest_per_gaussian();
  if (rest > 0) {
    h << "element sh " << scene.size() << "\n";
    for (int k = 0; k < rest; ++k) h << "property uchar f_rest_" << k << "\n";
  }
  h << "end_header\n";
  return h.str();
}

}  // namespace

unsigned quantise_unit(double t, int bits) {
  const double steps = double((1u << bits) - 1u);
  return static_cast<unsigned>(std::lround(std::clamp(t, 0.0, 1.0) * steps));
}

unsigned quantise_range(double v, double lo, double hi, int bits) {
  return hi > lo ? quantise_unit((v - lo) / (hi - lo), bits) : 0u;
}

void save_compressed_ply(const Scene& scene, const std::string& path, const SceneWriteOptions&) {
  const std::size_t n = scene.size();
  const std::size_t chunks = (n + kChunkGaussians - 1) / kChunkGaussians;
  const int rest = scene.sh_rest_per_gaussian(), per_channel = rest / 3;
  std::vector<float> bounds(chunks * kChunkFloats);
  std::vector<std::uint32_t> packed(n * 4);
  std::vector<std::uint8_t> sh(n * static_cast<std::size_t>(rest));
  for (std::size_t c = 0; c < chunks; ++c) {
    const std::size_t first = c * kChunkGaussians, last = std::min(n, first + kChunkGaussians);
    float* b = &bounds[c * kChunkFloats];
    chunk_bounds(scene, first, last, b);
    for (std::size_t i = first; i < last; ++i) {
      const double position[3] = {scene.positions[i * 3], scene.positions[i * 3 + 1], scene.positions[i * 3 + 2]};
      const double scale[3] = {log_scale(scene, i, 0), log_scale(scene, i, 1), log_scale(scene, i, 2)};
      std::uint32_t rgba = quantise_unit(scene.opacities[i], 8);
      for (int k = 0; k < 3; ++k) rgba |= quantise_range(colour(scene, i, k), b[12 + k], b[15 + k], 8) << (24 - 8 * k);
      std::uint32_t* word = &packed[i * 4];
      word[0] = pack_11_10_11(position, b, b + 3);
      word[1] = pack_rotation(&scene.rotations[i * 4]);
      word[2] = pack_11_10_11(scale, b + 6, b + 9);
      word[3] = rgba;
      // The file is channel-major (all R, then G, then B); the scene keeps [k][channel].
      for (int k = 0; k < per_channel; ++k)
        for (int ch = 0; ch < 3; ++ch)
          sh[i * rest + ch * per_channel + k] = pack_sh(scene.sh_rest[i * rest + k * 3 + ch]);
    }
  }
  write_file_atomically(path, [&](OutputFile& file) {
    file.write(header_for(scene, chunks));
    // Little endian, as the header says and as every host we build for.
    file.write(bounds.data(), bounds.size() * sizeof(float));
    file.write(packed.data(), packed.size() * sizeof(std::uint32_t));
    file.write(sh.data(), sh.size());
  });
}

}  // namespace flashgs
