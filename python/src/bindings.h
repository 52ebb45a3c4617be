// What the binding files of the Python module share: the objects Python holds and the functions
// that add each part of the API to the module.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include <pybind11/pybind11.h>

#include "flashgs/options.h"
#include "flashgs/scene.h"

namespace flashgs::python {

namespace py = pybind11;

// A scene as Python holds it: shared with the renderers that draw it and never changed after it
// is made (its arrays are read-only views), so a renderer keeps the copy it uploaded.
struct PyScene {
  std::shared_ptr<const Scene> scene;
  std::optional<LoadReport> report;  // what the loader dropped; none for a scene made from arrays
};

// RenderOptions with the kernel left to the scene (`kernel="auto"`) until the frame is drawn.
struct PyRenderOptions {
  RenderOptions options;
  bool kernel_auto = true;
  // The options for `scene`: its trained kernel where the kernel is "auto".
  RenderOptions resolved(const Scene& scene) const;
};

// A copy of `options` with each keyword of `values` set (a flashgs::Error naming a bad value, a
// TypeError naming an unknown keyword).
PyRenderOptions with_options(const PyRenderOptions& options, const py::kwargs& values);

// A kernel given as a SplatKernel or its text ("classic", "antialiased=0.1"); throws
// flashgs::Error naming `what` otherwise.
SplatKernel kernel_from(py::handle value, const std::string& what);

void bind_errors(py::module_& m);
void bind_scene(py::module_& m);
void bind_camera(py::module_& m);
void bind_options(py::module_& m);
void bind_stats(py::module_& m);
void bind_renderer(py::module_& m);

}  // namespace flashgs::python
