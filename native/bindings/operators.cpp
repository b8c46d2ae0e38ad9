// pybind11 bindings of the paper's further operators: diffusion smoothing, ray shooting, encoding
// onto a base, morphing, thin-sheet projection. Long calls release the GIL and take their thread
// count per call, like module.cpp (bindings.h).
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "pointscale/diffusion.h"
#include "pointscale/encoding.h"
#include "pointscale/morph.h"
#include "pointscale/ray_shooting.h"
#include "pointscale/sample_spacing.h"
#include "pointscale/validation.h"
#include "bindings.h"

namespace py = pybind11;
using namespace pointscale;
using namespace pointscale_bindings;

void bind_operators(py::module_& m) {
  m.def("taubin_mu", &taubin_mu, py::arg("lam"), py::arg("pass_band") = 0.1);

  m.def("diffuse", [](const DoubleArray& points, const DiffusionOptions& options, py::object progress, int threads) {
    const Points p = to_points(points);
    PythonProgress pp(progress);
    return without_gil(threads, [&] { return diffuse(p, options, ProgressStage{pp.get(), 0.0, 1.0}); });
  }, py::arg("points"), py::arg("options"), py::arg("progress") = py::none(), py::arg("threads") = 0);

  // onto_normals: the support's normals, or None to estimate them (MlsOptions::thin_sheets).
  m.def("project_sheets", [](const DoubleArray& points, const DoubleArray& onto, py::object onto_normals,
                             double kernel, MlsOptions options, double sheet, py::object progress, int threads) {
    const Points x = to_points(points), s = to_points(onto);
    check_kernel(kernel);
    const OptionalPoints given(onto_normals);
    options.sheet = sheet;
    if (given.present) options.support_normals = &given.p;
    else options.thin_sheets = true;
    PythonProgress pp(progress);
    MlsResult r = without_gil(threads, [&] {
      const SpatialIndex index(s);
      const Eigen::VectorXd h = kernel * local_spacing(index, 6);
      return mls_project(x, index, h, options, ProgressStage{pp.get(), 0.0, 1.0});
    });
    return py::make_tuple(r.positions, r.normals, r.not_converged, r.degenerate);
  }, py::arg("points"), py::arg("onto"), py::arg("onto_normals"), py::arg("kernel"), py::arg("mls"),
     py::arg("sheet"), py::arg("progress") = py::none(), py::arg("threads") = 0);

  m.def("shoot_rays", [](const DoubleArray& origins, const DoubleArray& directions, const DoubleArray& onto,
                         double kernel, const RayOptions& options, int threads) {
    const Points o = to_points(origins), d = to_points(directions), s = to_points(onto);
    check_kernel(kernel);
    RayHits r = without_gil(threads, [&] {
      const SpatialIndex index(s);
      return shoot_rays(o, d, index, kernel * local_spacing(index, 6), options);
    });
    py::array_t<bool> missed(static_cast<py::ssize_t>(r.missed.size()));
    std::copy(r.missed.begin(), r.missed.end(), missed.mutable_data());
    return py::make_tuple(r.positions, r.distances, missed);
  }, py::arg("origins"), py::arg("directions"), py::arg("onto"), py::arg("kernel"), py::arg("options"),
     py::arg("threads") = 0);

  m.def("encode", [](const DoubleArray& points, const DoubleArray& base, py::object base_normals,
                     const EncodeOptions& options, py::object progress, int threads) {
    const Points p = to_points(points), b = to_points(base);
    const OptionalPoints bn(base_normals);
    PythonProgress pp(progress);
    return without_gil(threads, [&] { return encode_onto(p, b, bn.get(), options, pp.get()); });
  }, py::arg("points"), py::arg("base"), py::arg("base_normals"), py::arg("options"),
     py::arg("progress") = py::none(), py::arg("threads") = 0);

  m.def("morph", [](const DoubleArray& a, const DoubleArray& b, const DoubleArray& base, py::object base_normals,
                    const MorphOptions& options, py::object progress, int threads) {
    const Points pa = to_points(a), pb = to_points(b), ps = to_points(base);
    const OptionalPoints bn(base_normals);
    PythonProgress pp(progress);
    MorphModel r = without_gil(threads, [&] { return morph(pa, pb, ps, bn.get(), options, pp.get()); });
    py::dict d;
    d["base"] = r.base;
    d["normals"] = r.normals;
    d["detail_a"] = r.detail_a;
    d["detail_b"] = r.detail_b;
    d["not_converged"] = r.not_converged;
    d["degenerate"] = r.degenerate;
    return d;
  }, py::arg("a"), py::arg("b"), py::arg("base"), py::arg("base_normals"), py::arg("options"),
     py::arg("progress") = py::none(), py::arg("threads") = 0);

  // Values at `points` from their k nearest of `onto` (alignment.nearest_indices).
  m.def("knn_interpolate", [](const DoubleArray& onto, const Eigen::VectorXd& values, const DoubleArray& points, int k,
                              int threads) {
    const Points f = to_points(onto), t = to_points(points);
    return without_gil(threads, [&] { return knn_interpolate(f, values, t, k); });
  }, py::arg("onto"), py::arg("values"), py::arg("points"), py::arg("k"), py::arg("threads") = 0);

  // diffusion: the "diffusion" smoother's settings, or None for the MLS smoother; rays: how the
  // finer levels are found from the coarser ones.
  m.def("decompose_rayshoot", [](const DoubleArray& points, py::object normals, const DecomposeOptions& options,
                                 const DiffusionOptions* diffusion, const RayOptions& rays, double fine_kernel,
                                 py::object progress, int threads) {
    const Points p = to_points(points);
    const OptionalPoints n(normals);
    RayshootReport report;
    PythonProgress pp(progress);
    MultiscaleModel model = without_gil(threads, [&] {
      return decompose_rayshoot(p, n.get(), options, diffusion, rays, fine_kernel, report, pp.get());
    });
    py::list missed;
    for (const auto& v : report.missed_points) missed.append(to_array(v));
    return py::make_tuple(std::move(model), missed);
  }, py::arg("points"), py::arg("normals"), py::arg("options"), py::arg("diffusion"), py::arg("rays"),
     py::arg("fine_kernel"), py::arg("progress") = py::none(), py::arg("threads") = 0);
}
