// Creates a rendering backend by name; the CUDA one only when built with CUDA.
#pragma once

#include <memory>
#include <string>

#include "flashgs/frame_memory.h"
#include "flashgs/renderer.h"

namespace flashgs::cli {

// "cpu", "cuda" (throws flashgs::Error when unavailable) or "auto" (CUDA if a device works).
// Prints which backend was chosen, and why, to stderr. `cpu_threads` and `cpu_blend` configure
// the CPU backend when it is the one chosen (0 threads: every core); `tuning` either backend.
std::unique_ptr<Renderer> create_backend(const std::string& which, int cpu_threads = 0,
                                         CpuBlend cpu_blend = CpuBlend::simd,
                                         const BackendTuning& tuning = tuning_from_environment());

// The kind of backend create_backend(which) makes, found without a word on stderr (estimates
// made before the backend is).
BackendKind backend_kind(const std::string& which);

// Whether `renderer` can queue frames behind each other without the host waiting for each (the
// CUDA backend: CudaRenderer::render_queued).
bool can_queue_frames(Renderer& renderer);

// Queues a frame behind the last one without waiting for it, as the viewer renders; `stats`
// gets this frame's counts and the previous frame's stage times. Only where can_queue_frames.
void render_queued(Renderer& renderer, const Camera& camera, const RenderOptions& options, FrameStats* stats);
// Waits until the frames render_queued queued have finished. Only where can_queue_frames.
void finish_queued_frames(Renderer& renderer);

// Renders a frame into `destination`, a device buffer of height x width x 3 floats (the CUDA
// backend: CudaRenderer::render_to_device), after the work queued on `producer_stream` (a
// cudaStream_t, 0 for none) so far; finished when it returns. Throws flashgs::Error naming
// `name` on another backend.
void render_to_device(Renderer& renderer, const Camera& camera, const RenderOptions& options, void* destination,
                      void* producer_stream, FrameStats* stats, const std::string& name);

}  // namespace flashgs::cli
