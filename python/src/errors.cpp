// flashgs.Error: a flashgs::Error raised in Python with the same one-line message the CLI prints.
#include <new>

#include "bindings.h"
#include "flashgs/error.h"

namespace flashgs::python {

void bind_errors(py::module_& m) {
  static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
  error.doc() = "Bad input or a failed operation: one line naming the file or option and the problem.";
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const Error& e) {
      error(printable_message(e.what()).c_str());
    } catch (const std::bad_alloc&) {
      // The renderers name a frame that did not fit; this is anything else that ran out.
      PyErr_SetString(PyExc_MemoryError, "out of memory");
    }
  });
}

}  // namespace flashgs::python
