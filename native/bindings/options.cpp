// The core's option structs as Python classes with named fields, built by keyword, so that a
// call from the pointscale package reads as the settings it passes (no row of bare numbers and
// flags). Only the plain settings are bound: the pointer fields (caching hints, given normals)
// stay with the binding that owns what they point to.
#include <pybind11/pybind11.h>

#include <string>

#include "pointscale/decomposition.h"
#include "pointscale/diffusion.h"
#include "pointscale/encoding.h"
#include "pointscale/mls_projection.h"
#include "pointscale/morph.h"
#include "pointscale/ray_shooting.h"
#include "pointscale/validation.h"

namespace py = pybind11;
using namespace pointscale;

void bind_options(py::module_& m) {
  const MlsOptions mls;
  py::class_<MlsOptions>(m, "MlsOptions", "The MLS projection's settings (mls_projection.h).")
      .def(py::init([](int neighbors, double tolerance, int max_iterations) {
             MlsOptions o;
             o.neighbors = neighbors;
             o.tolerance = tolerance;
             o.max_iterations = max_iterations;
             return o;
           }),
           py::kw_only(), py::arg("neighbors") = mls.neighbors, py::arg("tolerance") = mls.tolerance,
           py::arg("max_iterations") = mls.max_iterations)
      .def_readwrite("neighbors", &MlsOptions::neighbors)
      .def_readwrite("tolerance", &MlsOptions::tolerance)
      .def_readwrite("max_iterations", &MlsOptions::max_iterations)
      .def("validate", [](const MlsOptions& o) { validate(o); }, "Raises ValueError if a setting is out of range.");

  // `lambda` is a Python keyword, so the step is `lam` here, as in pointscale.smooth_diffusion.
  const DiffusionOptions dif;
  py::class_<DiffusionOptions>(m, "DiffusionOptions", "Laplacian (or Taubin) diffusion's settings (diffusion.h).")
      .def(py::init([](int neighbors, double lam, double mu, int iterations) {
             DiffusionOptions o;
             o.neighbors = neighbors;
             o.lambda = lam;
             o.mu = mu;
             o.iterations = iterations;
             return o;
           }),
           py::kw_only(), py::arg("neighbors") = dif.neighbors, py::arg("lam") = dif.lambda, py::arg("mu") = dif.mu,
           py::arg("iterations") = dif.iterations)
      .def_readwrite("neighbors", &DiffusionOptions::neighbors)
      .def_readwrite("lam", &DiffusionOptions::lambda)
      .def_readwrite("mu", &DiffusionOptions::mu)
      .def_readwrite("iterations", &DiffusionOptions::iterations)
      .def("validate", [](const DiffusionOptions& o, const std::string& prefix) { validate(o, prefix.c_str()); },
           py::arg("prefix") = "", "Raises ValueError if a setting is out of range; prefix starts the names of "
           "neighbors and iterations in the message (decompose's \"diffusion_\").");

  // The diffusion smoother goes to decompose as its own argument: the struct holds a pointer.
  const DecomposeOptions dec;
  py::class_<DecomposeOptions>(m, "DecomposeOptions", "decompose's settings (decomposition.h).")
      .def(py::init([](int levels, double decimation, double kernel, double max_variation, const MlsOptions& mls,
                       bool thin_sheets) {
             DecomposeOptions o;
             o.levels = levels;
             o.decimation = decimation;
             o.kernel = kernel;
             o.max_variation = max_variation;
             o.mls = mls;
             o.thin_sheets = thin_sheets;
             return o;
           }),
           py::kw_only(), py::arg("levels") = dec.levels, py::arg("decimation") = dec.decimation,
           py::arg("kernel") = dec.kernel, py::arg("max_variation") = dec.max_variation, py::arg("mls") = dec.mls,
           py::arg("thin_sheets") = dec.thin_sheets)
      .def_readwrite("levels", &DecomposeOptions::levels)
      .def_readwrite("decimation", &DecomposeOptions::decimation)
      .def_readwrite("kernel", &DecomposeOptions::kernel)
      .def_readwrite("max_variation", &DecomposeOptions::max_variation)
      .def_readwrite("mls", &DecomposeOptions::mls)
      .def_readwrite("thin_sheets", &DecomposeOptions::thin_sheets)
      .def("validate", [](const DecomposeOptions& o) { validate(o); }, "Raises ValueError if a setting is out of range.");

  const EncodeOptions enc;
  py::class_<EncodeOptions>(m, "EncodeOptions", "encode's settings (encoding.h).")
      .def(py::init([](double kernel, const MlsOptions& mls, double max_variation) {
             EncodeOptions o;
             o.kernel = kernel;
             o.mls = mls;
             o.max_variation = max_variation;
             return o;
           }),
           py::kw_only(), py::arg("kernel") = enc.kernel, py::arg("mls") = enc.mls,
           py::arg("max_variation") = enc.max_variation)
      .def_readwrite("kernel", &EncodeOptions::kernel)
      .def_readwrite("mls", &EncodeOptions::mls)
      .def_readwrite("max_variation", &EncodeOptions::max_variation)
      .def("validate", [](const EncodeOptions& o) { validate(o); }, "Raises ValueError if a setting is out of range.");

  const MorphOptions mor;
  py::class_<MorphOptions>(m, "MorphOptions", "morph's settings (morph.h).")
      .def(py::init([](double kernel, const MlsOptions& mls, int interpolation_neighbors) {
             MorphOptions o;
             o.kernel = kernel;
             o.mls = mls;
             o.interpolation_neighbors = interpolation_neighbors;
             return o;
           }),
           py::kw_only(), py::arg("kernel") = mor.kernel, py::arg("mls") = mor.mls,
           py::arg("interpolation_neighbors") = mor.interpolation_neighbors)
      .def_readwrite("kernel", &MorphOptions::kernel)
      .def_readwrite("mls", &MorphOptions::mls)
      .def_readwrite("interpolation_neighbors", &MorphOptions::interpolation_neighbors)
      .def("validate", [](const MorphOptions& o) { validate(o); }, "Raises ValueError if a setting is out of range.");

  const RayOptions ray;
  py::class_<RayOptions>(m, "RayOptions", "Ray shooting's settings (ray_shooting.h).")
      .def(py::init([](int neighbors, double tolerance, int max_iterations, double max_distance, double min_cosine) {
             RayOptions o;
             o.neighbors = neighbors;
             o.tolerance = tolerance;
             o.max_iterations = max_iterations;
             o.max_distance = max_distance;
             o.min_cosine = min_cosine;
             return o;
           }),
           py::kw_only(), py::arg("neighbors") = ray.neighbors, py::arg("tolerance") = ray.tolerance,
           py::arg("max_iterations") = ray.max_iterations, py::arg("max_distance") = ray.max_distance,
           py::arg("min_cosine") = ray.min_cosine)
      .def_readwrite("neighbors", &RayOptions::neighbors)
      .def_readwrite("tolerance", &RayOptions::tolerance)
      .def_readwrite("max_iterations", &RayOptions::max_iterations)
      .def_readwrite("max_distance", &RayOptions::max_distance)
      .def_readwrite("min_cosine", &RayOptions::min_cosine)
      .def("validate", [](const RayOptions& o) { validate(o); }, "Raises ValueError if a setting is out of range.");
}
