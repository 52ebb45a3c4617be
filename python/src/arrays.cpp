// Arrays between Python and the C++ scene (see arrays.h).
#include "arrays.h"

#include <utility>

#include "cuda_arrays.h"
#include "flashgs/error.h"

namespace flashgs::python {

namespace {

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

std::vector<py::ssize_t> byte_strides(const std::vector<py::ssize_t>& shape) {
  std::vector<py::ssize_t> strides(shape.size());
  py::ssize_t step = sizeof(float);
  for (std::size_t k = shape.size(); k-- > 0;) {
    strides[k] = step;
    step *= shape[k];
  }
  return strides;
}

std::string shape_text(const std::vector<py::ssize_t>& shape) {
  std::string text = "(";
  for (std::size_t k = 0; k < shape.size(); ++k) text += (k ? ", " : "") + std::to_string(shape[k]);
  return text + (shape.size() == 1 ? ",)" : ")");
}

// A __cuda_array_interface__ dictionary that we can read or write in one copy: float32,
// C-contiguous, unmasked.
struct CudaInterface {
  std::vector<py::ssize_t> shape;
  std::uintptr_t data = 0;
  bool readonly = false;
  bool has_stream = false;
  py::object stream;  // the "stream" entry (version 3)
};

CudaInterface contiguous_float_interface(const py::dict& interface, const std::string& name) {
  CudaInterface a;
  const std::string type = py::str(interface["typestr"]);
  for (py::handle extent : py::tuple(interface["shape"])) a.shape.push_back(extent.cast<py::ssize_t>());
  bool contiguous = true;  // strides None (or left out) mean C order
  if (interface.contains("strides") && !interface["strides"].is_none()) {
    std::vector<py::ssize_t> strides;
    for (py::handle stride : py::tuple(interface["strides"])) strides.push_back(stride.cast<py::ssize_t>());
    contiguous = strides == byte_strides(a.shape);
  }
  if (type != "<f4" || !contiguous)
    throw Error(name + ": a CUDA array must be contiguous float32 (it is " + type +
                (contiguous ? "" : ", strided") + "; use tensor.float().contiguous())");
  if (interface.contains("mask") && !interface["mask"].is_none())
    throw Error(name + ": masked CUDA arrays are not supported");
  const py::tuple data(interface["data"]);
  a.data = data[0].cast<std::uintptr_t>();
  a.readonly = data[1].cast<bool>();
  a.has_stream = interface.contains("stream");
  a.stream = a.has_stream ? py::object(interface["stream"]) : py::object(py::none());
  return a;
}

// The array described by a __cuda_array_interface__ dictionary, copied to the host.
py::array_t<float> copy_cuda_array(const py::dict& interface, const std::string& name) {
  const CudaInterface a = contiguous_float_interface(interface, name);
  py::array_t<float> host(a.shape);
  copy_from_device(host.mutable_data(), a.data, static_cast<std::size_t>(host.size()) * sizeof(float), name);
  return host;
}

}  // namespace

py::array_t<float> readonly_view(const std::vector<float>& values, const std::vector<py::ssize_t>& shape,
                                 py::handle owner) {
  py::array_t<float> view(shape, byte_strides(shape), values.data(), owner);
  view.attr("flags").attr("writeable") = false;
  return view;
}

py::array_t<float> array_owning(std::vector<float>&& values, const std::vector<py::ssize_t>& shape) {
  auto* owned = new std::vector<float>(std::move(values));
  py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::vector<float>*>(p); });
  return py::array_t<float>(shape, byte_strides(shape), owned->data(), free_when_done);
}

py::array_t<float> host_float_array(py::handle object, const std::string& name) {
  if (py::hasattr(object, "__cuda_array_interface__"))
    return copy_cuda_array(object.attr("__cuda_array_interface__").cast<py::dict>(), name);
  FloatArray array = FloatArray::ensure(object);
  if (!array)
    throw Error(name + ": expected an array of numbers (numpy, a torch tensor without grad, or a list), got " +
                std::string(py::str(py::type::handle_of(object).attr("__name__"))));
  return array;
}

DeviceArray writable_cuda_array(py::handle object, const std::string& name, const std::vector<py::ssize_t>& shape) {
  if (!py::hasattr(object, "__cuda_array_interface__"))
    throw Error(name + ": expected a CUDA array (e.g. a torch tensor on the GPU), got " +
                std::string(py::str(py::type::handle_of(object).attr("__name__"))));
  const CudaInterface a = contiguous_float_interface(object.attr("__cuda_array_interface__").cast<py::dict>(), name);
  if (a.shape != shape)
    throw Error(name + ": expected shape " + shape_text(shape) + " for the frame, got " + shape_text(a.shape));
  if (a.readonly) throw Error(name + ": the CUDA array is read-only");
  if (a.data == 0) throw Error(name + ": the CUDA array has no memory");
  DeviceArray d;
  d.data = reinterpret_cast<void*>(a.data);
  // Our frames run on a non-blocking stream, which follows no other: the copy into the array
  // waits for the producer's stream, an integer in version 3 of the interface (1 and 2 are the
  // legacy and per-thread default streams, handles the CUDA runtime takes as they are). None
  // says nothing is pending; without the entry (version 2) or with the ambiguous 0 we wait for
  // the legacy default stream, where such producers queue their work.
  if (!a.stream.is_none()) {
    const auto stream = a.stream.cast<std::uintptr_t>();
    d.stream = reinterpret_cast<void*>(stream != 0 ? stream : 1);
  } else if (!a.has_stream) {
    d.stream = reinterpret_cast<void*>(std::uintptr_t{1});
  }
  return d;
}

std::vector<float> checked_floats(const py::array_t<float>& array, const std::string& name,
                                  const std::vector<py::ssize_t>& shape) {
  bool fits = array.ndim() == static_cast<py::ssize_t>(shape.size());
  for (std::size_t k = 0; fits && k < shape.size(); ++k) fits = shape[k] < 0 || array.shape(k) == shape[k];
  if (!fits) {
    std::string expected = "(";
    for (std::size_t k = 0; k < shape.size(); ++k)
      expected += (k ? ", " : "") + (shape[k] < 0 ? std::string(k == 0 ? "N" : "K") : std::to_string(shape[k]));
    throw Error(name + ": expected shape " + expected + (shape.size() == 1 ? ",)" : ")") + ", got " +
                shape_text(array));
  }
  return std::vector<float>(array.data(), array.data() + array.size());
}

std::string shape_text(const py::array& array) {
  return shape_text(std::vector<py::ssize_t>(array.shape(), array.shape() + array.ndim()));
}

}  // namespace flashgs::python
