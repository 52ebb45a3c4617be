// Frame and scene memory estimates against the memory the system has available.
#include "memory_budget.h"

#include <cstdio>
#include <fstream>
#include <string>

#include <unistd.h>

#include "flashgs/scene.h"

namespace flashgs::viewer {
namespace {

constexpr std::uint64_t kFloatRgbBytes = 12;  // the renderer's image
constexpr std::uint64_t kRgba8Bytes = 4;      // the upload copy, and each texture
constexpr int kTile = 16;
// Per tile: the range start (8 bytes), a count per thread and the overlay's float count.
constexpr std::uint64_t kBytesPerTile = 64;
// What a backend keeps per Gaussian beside the scene: footprint, cull flag, blend record and
// a few tile pairs (renderer/src/cpu_frame.h); the CUDA backend keeps less on the host.
constexpr std::uint64_t kBackendBytesPerGaussian = 160;

std::string share_text(std::uint64_t available) {
  return memory_text(available) + " is available (at most " + std::to_string(int(kMemoryShare * 100)) +
         " % of it is used)";
}

}  // namespace

std::string memory_text(std::uint64_t bytes) {
  char text[32];
  if (bytes >= 100000000) std::snprintf(text, sizeof text, "%.1f GB", static_cast<double>(bytes) / 1e9);
  else std::snprintf(text, sizeof text, "%.0f MB", static_cast<double>(bytes) / 1e6);
  return text;
}

std::uint64_t frame_bytes(int width, int height, int texture_count) {
  if (width <= 0 || height <= 0) return 0;
  const std::uint64_t pixels = std::uint64_t(width) * std::uint64_t(height);
  const std::uint64_t tiles = std::uint64_t((width + kTile - 1) / kTile) * std::uint64_t((height + kTile - 1) / kTile);
  const std::uint64_t textures = texture_count > 0 ? std::uint64_t(texture_count) : 1;
  return pixels * (kFloatRgbBytes + kRgba8Bytes + kRgba8Bytes * textures) + tiles * kBytesPerTile;
}

std::uint64_t scene_bytes(std::uint64_t gaussians, std::uint64_t scene_bytes_per_gaussian) {
  return gaussians * (scene_bytes_per_gaussian + kBackendBytesPerGaussian);
}

std::uint64_t scene_bytes_per_gaussian(int sh_degree) {
  // position 3, scale 3, rotation 4, opacity 1, DC colour 3, then the higher bands.
  return (14 + std::uint64_t(sh_coefficient_count(sh_degree) - 1) * 3) * sizeof(float);
}

std::uint64_t available_memory_bytes() {
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  std::uint64_t kb = 0;
  std::string unit;
  while (meminfo >> key >> kb >> unit)
    if (key == "MemAvailable:") return kb * 1024;
#ifdef _SC_AVPHYS_PAGES
  const long pages = sysconf(_SC_AVPHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0) return std::uint64_t(pages) * std::uint64_t(page);
#endif
  return 0;
}

std::string frame_size_problem(int width, int height, int texture_count, int max_texture_size,
                               std::uint64_t available) {
  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  if (width < 1 || height < 1) return "a " + size + " frame has no pixels";
  const std::uint64_t need = frame_bytes(width, height, texture_count);
  if (max_texture_size > 0 && (width > max_texture_size || height > max_texture_size))
    return "a " + size + " frame is larger than OpenGL's texture limit of " + std::to_string(max_texture_size) +
           " pixels a side (it would need about " + memory_text(need) + " of memory)";
  if (available > 0 && double(need) > kMemoryShare * double(available))
    return "a " + size + " frame needs about " + memory_text(need) + " of memory, " + share_text(available);
  return "";
}

std::string scene_size_problem(std::uint64_t bytes, std::uint64_t available) {
  if (available > 0 && double(bytes) > kMemoryShare * double(available))
    return "the scene would need about " + memory_text(bytes) + " of memory, " + share_text(available);
  return "";
}

}  // namespace flashgs::viewer
