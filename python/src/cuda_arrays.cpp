// copy_from_device through the CUDA runtime (builds with the CUDA backend).
#include "cuda_arrays.h"

#include <cuda_runtime_api.h>

#include "flashgs/error.h"

namespace flashgs::python {

void copy_from_device(void* host, std::uintptr_t device, std::size_t bytes, const std::string& name) {
  if (bytes == 0) return;
  // cudaMemcpy waits for the work queued on the legacy default stream, which the producer's
  // stream (torch's default) synchronises with.
  const cudaError_t status =
      cudaMemcpy(host, reinterpret_cast<const void*>(device), bytes, cudaMemcpyDeviceToHost);
  if (status != cudaSuccess)
    throw Error(name + ": cannot copy the CUDA array to the host (" + cudaGetErrorString(status) + ")");
}

}  // namespace flashgs::python
