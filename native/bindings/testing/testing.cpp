// pointscale._testing: the core's internals for the tests and bench/, kept out of the _core
// module the package runs on. self_knn's rows are checked against a brute-force search, the
// kd-tree's rows are what self_knn replaced (bench/knn_bench.py), normals can be oriented
// with another graph width than the package's (tests/test_normals.py), and which parts an edit
// mirrors can be asked directly (tests/test_mirrored_edits.py), and which threads a parallel
// loop's chunks ran on, in what rounding mode, can be seen (tests/test_threads.py).
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <cfenv>
#include <chrono>
#include <cstddef>
#include <thread>
#include <vector>

#include "../bindings.h"
#include "pointscale/mirrored_parts.h"
#include "pointscale/oriented_normals.h"
#include "pointscale/parallel.h"
#include "pointscale/self_knn.h"
#include "pointscale/spatial_index.h"

namespace py = pybind11;
using namespace pointscale;
using namespace pointscale_bindings;

namespace {

// (#P by k indices, #P by k squared distances) of every point's k nearest among `points`,
// which fill(index, rows, distances) writes straight into the NumPy arrays (no copy to time).
template <class Fill>
py::tuple knn_rows(const DoubleArray& points, int k, int threads, const Fill& fill) {
  Points p = to_points(points);
  if (k < 1 || k > p.rows()) throw py::value_error("k must be between 1 and the number of points");
  const std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(p.rows()), k};
  py::array_t<Index> nearest(shape);
  py::array_t<double> d2(shape);
  Index* rows = nearest.mutable_data();
  double* dist = d2.mutable_data();
  without_gil(threads, [&] {
    fill(SpatialIndex(p), rows, dist);
    return 0;
  });
  return py::make_tuple(nearest, d2);
}

// A number per thread that asks for one: the first thread to ask gets 1, the next 2, ...
int thread_number() {
  static std::atomic<int> next{1};
  thread_local const int mine = next.fetch_add(1);
  return mine;
}

}  // namespace

PYBIND11_MODULE(_testing, m) {
  m.doc() = "The core's internals for tests and benchmarks; not part of pointscale's API.";

  // (thread numbers, rounding modes) of the chunks of a parallel loop of `chunks` chunks, each
  // busy for about `busy_us` microseconds, run with `threads` threads from a calling thread whose
  // rounding is upward when `upward` (restored after). thread_number() of the caller comes
  // first. The mode is 1 where a chunk rounded upward, 0 where it rounded to nearest.
  m.def("loop_threads", [](int chunks, int busy_us, int threads, bool upward) {
    if (chunks < 1 || busy_us < 0) throw py::value_error("chunks must be positive and busy_us not negative");
    std::vector<int> number(static_cast<std::size_t>(chunks)), mode(static_cast<std::size_t>(chunks));
    const int caller = without_gil(threads, [&] {
      const int before = std::fegetround();
      if (upward) std::fesetround(FE_UPWARD);
      parallel_for(static_cast<std::size_t>(chunks), [&](std::size_t b, std::size_t e) {
        for (std::size_t c = b; c < e; ++c) {
          const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(busy_us);
          while (std::chrono::steady_clock::now() < until) {}
          number[c] = thread_number();
          mode[c] = std::fegetround() == FE_UPWARD ? 1 : 0;
        }
      }, {}, 1);
      std::fesetround(before);
      return thread_number();
    });
    return py::make_tuple(caller, number, mode);
  }, py::arg("chunks"), py::arg("busy_us"), py::arg("threads") = 0, py::arg("upward") = false);

  // Every point's k nearest among the points themselves (the rows decompose's kNN passes use).
  m.def("self_knn", [](const DoubleArray& points, int k, int threads) {
    return knn_rows(points, k, threads, [&](const SpatialIndex& index, Index* rows, double* dist) {
      self_knn(index, k, [&](Index i, const Index* idx, const double* d, int found) {
        std::copy(idx, idx + found, rows + static_cast<std::size_t>(i) * k);
        std::copy(d, d + found, dist + static_cast<std::size_t>(i) * k);
      });
    });
  }, py::arg("points"), py::arg("k"), py::arg("threads") = 0);

  // The same rows from a kd-tree query per point.
  m.def("kdtree_knn", [](const DoubleArray& points, int k, int threads) {
    return knn_rows(points, k, threads, [&](const SpatialIndex& index, Index* rows, double* dist) {
      parallel_for(static_cast<std::size_t>(index.size()), [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i)
          index.knn(index.points().row(static_cast<Eigen::Index>(i)).data(), k, rows + i * k, dist + i * k);
      });
    });
  }, py::arg("points"), py::arg("k"), py::arg("threads") = 0);

  // Oriented normals with the orientation graph's width given (oriented_normals.h).
  m.def("oriented_normals", [](const DoubleArray& points, int neighbors, int width, int threads) {
    Points p = to_points(points);
    return without_gil(threads, [&] { return oriented_normals(std::move(p), neighbors, width); });
  }, py::arg("points"), py::arg("neighbors"), py::arg("width") = orientation_width, py::arg("threads") = 0);

  // Which points lie in a part that an edited base (#P by 3, in the model's coordinates: the
  // package's world coordinates less the decomposition's origin) mirrors (mirrored_parts.h): #P
  // flags, all 0 when none.
  m.def("mirrored_points", [](const MultiscaleModel& model, const DoubleArray& edited, int threads) {
    const Points e = to_points(edited);
    const std::vector<unsigned char> flags = without_gil(threads, [&] { return mirrored_parts(model, e); });
    return py::array_t<unsigned char>(static_cast<py::ssize_t>(flags.size()), flags.data());
  }, py::arg("model"), py::arg("edited"), py::arg("threads") = 0);
}
