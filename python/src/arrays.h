// Arrays between Python and the C++ scene: read-only numpy views of a scene's vectors, and float
// arrays read from numpy, anything numpy converts (torch CPU tensors, lists) or CUDA arrays.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

namespace flashgs::python {

namespace py = pybind11;

// A read-only float32 view of `values` with `shape`, keeping `owner` (which holds them) alive.
py::array_t<float> readonly_view(const std::vector<float>& values, const std::vector<py::ssize_t>& shape,
                                 py::handle owner);

// A float32 array whose memory is `values`, moved into it (no copy).
py::array_t<float> array_owning(std::vector<float>&& values, const std::vector<py::ssize_t>& shape);

// A C-ordered float32 array read from `object`: a numpy array or anything numpy converts, or an
// object with __cuda_array_interface__ (copied from the device). Throws flashgs::Error naming
// `name` when it is none of these.
py::array_t<float> host_float_array(py::handle object, const std::string& name);

// A CUDA array to write a frame into: its device address and the stream whose work so far it
// depends on (a cudaStream_t; null: none).
struct DeviceArray {
  void* data = nullptr;
  void* stream = nullptr;
};

// `object`'s __cuda_array_interface__ when it is a writable, C-contiguous float32 array of
// `shape`; throws flashgs::Error naming `name` otherwise.
DeviceArray writable_cuda_array(py::handle object, const std::string& name, const std::vector<py::ssize_t>& shape);

// The rows of `array` (shape (rows, columns...)) as floats, after checking its shape: `dims`
// dimensions, each of `shape` equal where it is not -1. Throws flashgs::Error naming `name`.
std::vector<float> checked_floats(const py::array_t<float>& array, const std::string& name,
                                  const std::vector<py::ssize_t>& shape);

// The shape of `array` as "(2, 3)", for messages.
std::string shape_text(const py::array& array);

}  // namespace flashgs::python
