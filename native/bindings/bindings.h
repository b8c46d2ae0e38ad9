// What every binding file needs to hand work to the core: NumPy arrays as the core's matrices,
// a Python progress callable as the core's ProgressCallback, and a call that runs without the
// GIL on the number of threads the caller asked for.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <utility>
#include <vector>

#include "pointscale/parallel.h"
#include "pointscale/progress.h"
#include "pointscale/types.h"

namespace pointscale_bindings {

namespace py = pybind11;
using pointscale::Index;
using pointscale::Points;
using pointscale::Vec3;

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using IndexArray = py::array_t<Index, py::array::c_style | py::array::forcecast>;

// An (n, 3) array as the core's points (a copy: the core keeps and reorders its own).
inline Points to_points(const DoubleArray& a) {
  if (a.ndim() != 2 || a.shape(1) != 3) throw std::invalid_argument("expected an (n, 3) array");
  Points p(a.shape(0), 3);
  std::copy(a.data(), a.data() + a.size(), p.data());
  return p;
}

// An origin of 3 numbers, or zero for None.
inline Vec3 to_origin(const py::object& origin) {
  if (origin.is_none()) return Vec3::Zero();
  const DoubleArray o = origin.cast<DoubleArray>();
  if (o.size() != 3) throw std::invalid_argument("expected an origin of 3 numbers");
  return Vec3(o.data()[0], o.data()[1], o.data()[2]);
}

// The points minus origin, in one copy (centring in NumPy first would hold a second one).
inline Points to_points_centred(const DoubleArray& a, const Vec3& origin) {
  Points p = to_points(a);
  p.rowwise() -= origin.transpose();
  return p;
}

// An optional (n, 3) array: None gives no points and get() nullptr, as the core takes it.
struct OptionalPoints {
  Points p;
  bool present = false;
  explicit OptionalPoints(const py::object& o) {
    if (o.is_none()) return;
    p = to_points(o.cast<DoubleArray>());
    present = true;
  }
  const Points* get() const { return present ? &p : nullptr; }
};

template <class T>
py::array_t<T> to_array(const std::vector<T>& v, std::vector<py::ssize_t> shape) {
  py::array_t<T> out(shape);
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

template <class T>
py::array_t<T> to_array(const std::vector<T>& v) {
  return to_array(v, {static_cast<py::ssize_t>(v.size())});
}

// Wraps a Python callable as a ProgressCallback. A Python exception raised inside it cancels the
// work and is re-raised once the GIL is back.
// Without one (None), a call from the main thread still looks for Ctrl-C every 100 ms: Python
// runs its signal handlers only when it holds the GIL, so a decompose of a large scan went on
// to its end, 12 s, before KeyboardInterrupt was raised.
struct PythonProgress {
  py::object callable;
  pointscale::ProgressCallback callback;
  std::chrono::steady_clock::time_point last_look{};
  explicit PythonProgress(py::object c) : callable(std::move(c)) {
    if (callable.is_none()) {
      const py::object threading = py::module_::import("threading");
      if (!threading.attr("current_thread")().is(threading.attr("main_thread")())) return;
      last_look = std::chrono::steady_clock::now();
      callback = [this](double) -> bool {
        const auto now = std::chrono::steady_clock::now();
        if (now - last_look < std::chrono::milliseconds(100)) return true;
        last_look = now;
        py::gil_scoped_acquire gil;
        return PyErr_CheckSignals() == 0;  // an exception (KeyboardInterrupt) stays set: re-raised
      };
      return;
    }
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

// Runs f without the GIL on `threads` threads (0: all cores) for this call only; turns a
// cancellation caused by a Python exception into that exception. The count is set on the
// calling thread for the duration of f (ThreadCountScope), so another Python thread calling
// the core at the same time keeps its own count, and nothing is left set afterwards.
template <class F>
auto without_gil(int threads, F&& f) {
  try {
    pointscale::ThreadCountScope scope(threads);
    py::gil_scoped_release release;
    return f();
  } catch (const pointscale::Cancelled&) {
    if (PyErr_Occurred()) throw py::error_already_set();
    throw;
  }
}

}  // namespace pointscale_bindings
