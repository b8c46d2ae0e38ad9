// What both binding files need to run the core from Python: a Python progress callable as
// the core's ProgressCallback, and a call without the GIL that gives back the callable's own
// exception when it stopped the work.
#pragma once
#include <pybind11/pybind11.h>

#include <utility>

#include "pointscale/progress.h"

namespace pointscale_bindings {

namespace py = pybind11;

// Wraps a Python callable as a ProgressCallback. A Python exception raised inside it cancels the
// work and is re-raised once the GIL is back.
struct PythonProgress {
  py::object callable;
  pointscale::ProgressCallback callback;
  explicit PythonProgress(py::object c) : callable(std::move(c)) {
    if (callable.is_none()) return;
    callback = [this](double fraction) -> bool {
      py::gil_scoped_acquire gil;
      py::object r;
      try {
        r = callable(fraction);
      } catch (py::error_already_set& e) {
        e.restore();
        return false;
      }
      if (r.is_none()) return true;
      try {
        return r.cast<bool>();
      } catch (const py::cast_error&) {  // a string, a list...: a ValueError, not pybind's cast error
        PyErr_Format(PyExc_ValueError, "progress must return True, False or None, got a %s", Py_TYPE(r.ptr())->tp_name);
        return false;
      }
    };
  }
  const pointscale::ProgressCallback* get() const { return callback ? &callback : nullptr; }
};

// Runs f without the GIL; turns a cancellation caused by a Python exception into that exception.
template <class F>
auto without_gil(F&& f) {
  try {
    py::gil_scoped_release release;
    return f();
  } catch (const pointscale::Cancelled&) {
    if (PyErr_Occurred()) throw py::error_already_set();
    throw;
  }
}

}  // namespace pointscale_bindings
