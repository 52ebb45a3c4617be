// What one frame of a backend needs in memory, estimated before rendering, and how much memory
// this process can still get: a frame that cannot fit is refused with both figures.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace flashgs {

enum class BackendKind { cpu, cuda };

// Bytes by purpose; host is what lives in this process's memory, device what lives on the GPU.
struct FrameMemory {
  std::uint64_t image = 0;         // the float RGB frame (host; on CUDA also on the device)
  std::uint64_t per_gaussian = 0;  // footprints, cull flags, blend data
  std::uint64_t per_tile = 0;      // tile ranges, per-thread tile histograms (CPU)
  std::uint64_t pairs = 0;         // Gaussian-tile keys and their sort buffers
  std::uint64_t host = 0;
  std::uint64_t device = 0;
};

// The working memory of a width x height frame of `gaussians` Gaussians with `pairs`
// Gaussian-tile pairs (unknown before a frame is rendered: pass the last frame's kv_pairs, or
// the Gaussian count as a floor). `threads`: the CPU backend's thread count (its per-thread
// tile histograms); ignored for CUDA.
FrameMemory estimate_frame_memory(BackendKind backend, std::size_t gaussians, int width, int height,
                                  std::uint64_t pairs, int threads);

// Memory this process can still allocate: the least of the system's available memory
// (/proc/meminfo MemAvailable), the address-space limit (RLIMIT_AS) less what is mapped, and
// the cgroup's memory.max less its use. `limited_by` names the binding one. 0 bytes with
// limited_by empty when none of them can be read.
struct AvailableMemory {
  std::uint64_t bytes = 0;
  std::string limited_by;
};
AvailableMemory available_host_memory();
// The system's part of it alone (MemAvailable; 0 when unknown): the viewer checks a window's
// frames against it and leaves a process limit to the allocation that fails (it then falls
// back to the last size that rendered).
std::uint64_t system_available_memory();

// "a 51200x28800 frame needs about 18.1 GB (image 17.7 GB, tiles 0.4 GB, ...) but 3.9 GB is
// available (address-space limit)" when the estimate's host part exceeds `available`;
// empty when it fits (or the available memory is unknown).
std::string frame_memory_shortfall(const FrameMemory& need, int width, int height, const AvailableMemory& available);

// "12.3 GB", "512.0 MB", "2728 bytes": a byte count for messages.
std::string format_bytes(std::uint64_t bytes);
// A byte count computed in floating point (a header's count times a record size), saturated
// at the largest std::uint64_t for format_bytes.
std::uint64_t byte_count(double bytes);

}  // namespace flashgs
