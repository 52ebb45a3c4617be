// Frame and scene memory estimates against the memory the system has available.
#include "memory_budget.h"

#include <thread>

#include "count_text.h"
#include "flashgs/frame_memory.h"
#include "flashgs/scene.h"

namespace flashgs::viewer {
namespace {

constexpr std::uint64_t kRgba8Bytes = 4;  // the upload copy, and each texture
// Tile pairs per Gaussian that the scene's memory estimate allows for (pc_playbot at 1080p: 3.1
// with flash, 7.6 with the baseline, whose pairs are counted when the frame is sized).
constexpr std::uint64_t kPairsPerGaussian = 4;

std::string share_text(std::uint64_t available) {
  return format_bytes(available) + " is available (at most " + std::to_string(int(kMemoryShare * 100)) +
         " % of it is used)";
}

}  // namespace

std::uint64_t frame_bytes(int width, int height, int texture_count) {
  if (width <= 0 || height <= 0) return 0;
  const std::uint64_t pixels = std::uint64_t(width) * std::uint64_t(height);
  const std::uint64_t textures = texture_count > 0 ? std::uint64_t(texture_count) : 1;
  const int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const FrameMemory renderer = estimate_frame_memory(BackendKind::cpu, 0, width, height, 0, threads);
  return renderer.host + pixels * (kRgba8Bytes + kRgba8Bytes * textures);
}

std::uint64_t scene_bytes(std::uint64_t gaussians, std::uint64_t scene_bytes_per_gaussian) {
  // What the CPU backend keeps per Gaussian beside the scene (the CUDA backend keeps less on
  // the host): its per-Gaussian arrays and a few tile pairs.
  const FrameMemory backend =
      estimate_frame_memory(BackendKind::cpu, gaussians, 0, 0, gaussians * kPairsPerGaussian, 1);
  return gaussians * scene_bytes_per_gaussian + backend.per_gaussian + backend.pairs;
}

std::uint64_t scene_bytes_per_gaussian(int sh_degree) {
  // position 3, scale 3, rotation 4, opacity 1, DC colour 3, then the higher bands.
  return (14 + std::uint64_t(sh_coefficient_count(sh_degree) - 1) * 3) * sizeof(float);
}

std::string frame_size_problem(int width, int height, int texture_count, int max_texture_size,
                               std::uint64_t available) {
  const std::string size = size_text(width, height);
  if (width < 1 || height < 1) return "a " + size + " frame has no pixels";
  const std::uint64_t need = frame_bytes(width, height, texture_count);
  if (max_texture_size > 0 && (width > max_texture_size || height > max_texture_size))
    return "a " + size + " frame is larger than OpenGL's texture limit of " + std::to_string(max_texture_size) +
           " pixels a side (it would need about " + format_bytes(need) + " of memory)";
  if (available > 0 && double(need) > kMemoryShare * double(available))
    return "a " + size + " frame needs about " + format_bytes(need) + " of memory, " + share_text(available);
  return "";
}

std::string scene_size_problem(std::uint64_t bytes, std::uint64_t available) {
  if (available > 0 && double(bytes) > kMemoryShare * double(available))
    return "the scene would need about " + format_bytes(bytes) + " of memory, " + share_text(available);
  return "";
}

}  // namespace flashgs::viewer
