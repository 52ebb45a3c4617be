// The extension module flashgs._flashgs: each part of the API is added by its own binding file.
#include "bindings.h"

PYBIND11_MODULE(_flashgs, m) {
  using namespace flashgs::python;
  m.doc() = "FlashGS: a 3D Gaussian Splatting renderer (the compiled part of the flashgs package)";
#ifdef FLASHGS_HAVE_CUDA
  m.attr("has_cuda") = true;
#else
  m.attr("has_cuda") = false;
#endif
  m.attr("__version__") = FLASHGS_VERSION;
  bind_errors(m);
  bind_options(m);
  bind_scene(m);
  bind_camera(m);
  bind_stats(m);
  bind_renderer(m);
}
