// Memory estimates for the viewer's frames and scenes, checked before a size is used so that too large a request is refused with its figure instead of ending in std::bad_alloc.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace flashgs::viewer {

// Host bytes a width x height frame takes on the viewer's paths: the CPU renderer's frame
// without its Gaussians and pairs (flashgs::estimate_frame_memory: the float RGB image and the
// per-tile tables), the 8-bit copy uploaded to the texture and the texture(s) themselves (host
// memory on Mesa). Pairs depend on the scene and are not counted.
std::uint64_t frame_bytes(int width, int height, int texture_count);
// Bytes `gaussians` Gaussians take in the scene plus a backend's per-Gaussian working memory.
std::uint64_t scene_bytes(std::uint64_t gaussians, std::uint64_t scene_bytes_per_gaussian);

// Bytes one Gaussian of SH degree `sh_degree` takes in a Scene (positions to sh_rest).
std::uint64_t scene_bytes_per_gaussian(int sh_degree);


// At most this share of the available memory goes to one frame or one scene request.
inline constexpr double kMemoryShare = 0.75;

// Empty when a width x height frame fits, else the reason with the figures, e.g. "a 32768x28800
// frame needs about 18.9 GB of memory, 22.0 GB is available (at most 75 % of it is used)".
// `max_texture_size` is OpenGL's limit (0: none known); `available` (from
// flashgs::system_available_memory) 0: memory not checked.
std::string frame_size_problem(int width, int height, int texture_count, int max_texture_size,
                               std::uint64_t available);
// The same for a scene of `bytes` (what the viewer would generate or tile): "the scene would
// need about ...".
std::string scene_size_problem(std::uint64_t bytes, std::uint64_t available);


}  // namespace flashgs::viewer
