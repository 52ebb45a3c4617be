// copy_from_device in a build without the CUDA backend: a CUDA array cannot be read.
#include "cuda_arrays.h"

#include "flashgs/error.h"

namespace flashgs::python {

void copy_from_device(void*, std::uintptr_t, std::size_t, const std::string& name) {
  throw Error(name + ": a CUDA array, but this build has no CUDA backend (move it to the CPU first, "
                     "e.g. tensor.cpu())");
}

}  // namespace flashgs::python
