// Backend selection for the CLI (CPU only until the CUDA backend is linked in).
#include "backend_factory.h"

#include <cstdio>

#include "flashgs/error.h"

#ifdef FLASHGS_HAVE_CUDA
#include <cuda_runtime_api.h>

#include "flashgs/cuda_renderer.h"
#endif

namespace flashgs::cli {

std::unique_ptr<Renderer> create_backend(const std::string& which, int cpu_threads, CpuBlend cpu_blend,
                                         const BackendTuning& tuning) {
#ifdef FLASHGS_HAVE_CUDA
  if (which == "cuda" || which == "auto") {
    std::string why;
    if (cuda_available(&why)) return make_cuda_renderer(tuning);
    if (which == "cuda") throw Error("the CUDA backend is unavailable: " + why);
    std::fprintf(stderr, "note: no usable CUDA device (%s); rendering on the CPU\n", why.c_str());
  }
#else
  if (which == "cuda") throw Error("this build has no CUDA backend (configure with -DFLASHGS_WITH_CUDA=ON)");
#endif
  return make_cpu_renderer(cpu_threads, cpu_blend, tuning);
}

BackendKind backend_kind(const std::string& which) {
#ifdef FLASHGS_HAVE_CUDA
  std::string why;
  if ((which == "cuda" || which == "auto") && cuda_available(&why)) return BackendKind::cuda;
#else
  (void)which;
#endif
  return BackendKind::cpu;
}

bool can_queue_frames(Renderer& renderer) {
#ifdef FLASHGS_HAVE_CUDA
  return dynamic_cast<CudaRenderer*>(&renderer) != nullptr;
#else
  (void)renderer;
  return false;
#endif
}

void render_queued(Renderer& renderer, const Camera& camera, const RenderOptions& options, FrameStats* stats) {
#ifdef FLASHGS_HAVE_CUDA
  if (auto* cuda = dynamic_cast<CudaRenderer*>(&renderer)) {
    cuda->render_queued(camera, options, stats);
    return;
  }
#else
  (void)camera, (void)options, (void)stats;
#endif
  throw Error("internal error: the " + renderer.name() + " backend cannot queue frames");
}

void finish_queued_frames(Renderer& renderer) {
#ifdef FLASHGS_HAVE_CUDA
  if (auto* cuda = dynamic_cast<CudaRenderer*>(&renderer)) {
    cuda->finish();
    return;
  }
#endif
  throw Error("internal error: the " + renderer.name() + " backend cannot queue frames");
}

void render_to_device(Renderer& renderer, const Camera& camera, const RenderOptions& options, void* destination,
                      void* producer_stream, FrameStats* stats, const std::string& name) {
#ifdef FLASHGS_HAVE_CUDA
  if (auto* cuda = dynamic_cast<CudaRenderer*>(&renderer)) {
    if (producer_stream) {  // the frame's copy into the buffer waits for the producer's work
      cudaEvent_t produced = nullptr;
      cudaError_t status = cudaEventCreateWithFlags(&produced, cudaEventDisableTiming);
      if (status == cudaSuccess) status = cudaEventRecord(produced, static_cast<cudaStream_t>(producer_stream));
      if (status == cudaSuccess) status = cudaStreamWaitEvent(static_cast<cudaStream_t>(cuda->stream()), produced, 0);
      if (produced) cudaEventDestroy(produced);
      if (status != cudaSuccess)
        throw Error(name + ": cannot wait for the stream that made it (" + cudaGetErrorString(status) + ")");
    }
    cuda->render_to_device(camera, options, destination, stats);
    return;
  }
#else
  (void)camera, (void)options, (void)destination, (void)producer_stream, (void)stats;
#endif
  throw Error(name + ": the " + renderer.name() + " backend renders into host memory; a CUDA array needs backend=\"cuda\"");
}

}  // namespace flashgs::cli
