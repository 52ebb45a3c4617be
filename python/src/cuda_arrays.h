// Reading an array that lives on a CUDA device (its __cuda_array_interface__) into host memory.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace flashgs::python {

// Copies `bytes` from device address `device` to `host`; throws flashgs::Error naming `name`
// when the copy fails or this build has no CUDA backend.
void copy_from_device(void* host, std::uintptr_t device, std::size_t bytes, const std::string& name);

}  // namespace flashgs::python
