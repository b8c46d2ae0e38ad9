// The core's checks (validation.h) for the pointscale package, which calls them where it must
// check an input before it centres it, and reads the supported limits from `limits`: each check
// and each limit is defined once, in the core. The entry points make the same checks again on
// what they are given, for C++ callers.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>

#include <string>

#include "pointscale/validation.h"
#include "bindings.h"

namespace py = pybind11;
using namespace pointscale;
using namespace pointscale_bindings;

void bind_validation(py::module_& m) {
  py::dict limits;
  limits["max_coordinate"] = max_coordinate;
  limits["max_extent"] = max_extent;
  limits["min_extent"] = min_extent;
  limits["max_threads"] = max_threads;
  limits["max_levels"] = max_levels;
  limits["max_neighbors"] = max_neighbors;
  limits["max_iterations"] = max_iterations;
  limits["max_diffusion_iterations"] = max_diffusion_iterations;
  limits["max_diffusion_growth"] = max_diffusion_growth;
  limits["min_kernel"] = min_kernel;
  limits["max_kernel"] = max_kernel;
  limits["max_gain"] = max_gain;
  limits["min_coarse_points"] = min_coarse_points;
  m.attr("limits") = limits;

  // The arrays come as C-contiguous float64 (n, 3) NumPy arrays and are read in place.
  m.def("check_points", [](const PointsRef& points, const std::string& name, Eigen::Index min_count) {
    check_points(points, name.c_str(), min_count);
  }, py::arg("points"), py::arg("name") = "points", py::arg("min_count") = 1);
  m.def("check_normals", [](const DoubleArray& normals, const PointsRef& points, const std::string& name,
                            const std::string& points_name) {
    const Points n = to_points(normals);
    check_normals(&n, points, name.c_str(), points_name.c_str());
  }, py::arg("normals"), py::arg("points"), py::arg("name") = "normals", py::arg("points_name") = "points");
  m.def("check_surface", [](const PointsRef& points, const std::string& name, bool allow_planar) {
    check_surface(points, name.c_str(), allow_planar);
  }, py::arg("points"), py::arg("name") = "points", py::arg("allow_planar") = false);
  m.def("check_extent", [](const PointsRef& points, const std::string& name, bool minimum) {
    return check_extent(points, name.c_str(), minimum);
  }, py::arg("points"), py::arg("name") = "points", py::arg("minimum") = true);
  m.def("check_near", [](const PointsRef& points, const Vec3& centre, const std::string& name,
                         const std::string& other) { check_near(points, centre, name.c_str(), other.c_str()); },
        py::arg("points"), py::arg("centre"), py::arg("name"), py::arg("other"));
  m.def("check_stable_diffusion", [](double lam, double mu, long long iterations, const std::string& name) {
    check_stable_diffusion(lam, mu, iterations, name.c_str());
  }, py::arg("lam"), py::arg("mu"), py::arg("iterations"), py::arg("name") = "iterations");
  m.def("check_threads", &check_threads, py::arg("threads"));
  m.def("points_needed", [](const DecomposeOptions& options, const std::string& what) {
    return points_needed(options, what.c_str());
  }, py::arg("options"), py::arg("what") = "decompose");
  // As decompose and decompose_rayshoot check their input: the package calls it on the raw
  // points, before it centres them or estimates thin sheets' sides from them.
  m.def("check_decompose_input", [](const PointsRef& points, py::object normals, DecomposeOptions options,
                                    const DiffusionOptions* diffusion, const std::string& what) {
    const OptionalPoints n(normals);
    options.diffusion = diffusion;
    // With none given, _core.decompose(estimate_sides=True) estimates the sides later.
    options.thin_sheets = options.thin_sheets && n.present;
    check_decompose_input(points, n.get(), options, what.c_str());
  }, py::arg("points"), py::arg("normals"), py::arg("options"), py::arg("diffusion") = py::none(),
     py::arg("what") = "decompose");
}
