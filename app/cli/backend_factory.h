// Creates a rendering backend by name; the CUDA one only when built with CUDA.
#pragma once

#include <memory>
#include <string>

#include "flashgs/renderer.h"

namespace flashgs::cli {

// "cpu", "cuda" (throws flashgs::Error when unavailable) or "auto" (CUDA if a device works).
// Prints which backend was chosen, and why, to stderr. `cpu_threads` and `cpu_blend` configure
// the CPU backend when it is the one chosen (0 threads: every core).
std::unique_ptr<Renderer> create_backend(const std::string& which, int cpu_threads = 0,
                                         CpuBlend cpu_blend = CpuBlend::simd);

}  // namespace flashgs::cli
