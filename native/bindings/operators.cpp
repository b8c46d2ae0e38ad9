// pybind11 bindings of the paper's further operators: diffusion smoothing, ray shooting, encoding
// onto a base, morphing, thin-sheet projection. Long calls release the GIL, like module.cpp.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "pointscale/diffusion.h"
#include "pointscale/encoding.h"
#include "pointscale/morph.h"
#include "pointscale/ray_shooting.h"
#include "pointscale/sample_spacing.h"
#include "python_progress.h"

namespace py = pybind11;
using namespace pointscale;
using pointscale_bindings::PythonProgress;
using pointscale_bindings::without_gil;

namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

Points to_points(const DoubleArray& a) {
  if (a.ndim() != 2 || a.shape(1) != 3) throw std::invalid_argument("expected an (n, 3) array");
  Points p(a.shape(0), 3);
  std::copy(a.data(), a.data() + a.size(), p.data());
  return p;
}

// Optional (n, 3) array: None gives an empty matrix and has() false.
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

MlsOptions mls_options(int neighbors, double tolerance, int max_iterations) {
  MlsOptions o;
  o.neighbors = neighbors;
  o.tolerance = tolerance;
  o.max_iterations = max_iterations;
  return o;
}

py::array_t<Index> index_array(const IndexList& v) {
  py::array_t<Index> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

}  // namespace

void bind_operators(py::module_& m) {
  m.def("taubin_mu", &taubin_mu, py::arg("lam"), py::arg("pass_band") = 0.1);

  m.def("diffuse", [](const DoubleArray& points, int neighbors, double lam, double mu, int iterations,
                      py::object progress) {
    const Points p = to_points(points);
    DiffusionOptions o;
    o.neighbors = neighbors;
    o.lambda = lam;
    o.mu = mu;
    o.iterations = iterations;
    PythonProgress pp(progress);
    return without_gil([&] { return diffuse(p, o, ProgressStage{pp.get(), 0.0, 1.0}); });
  });

  m.def("project_sheets", [](const DoubleArray& points, const DoubleArray& onto, py::object onto_normals,
                             double kernel, int neighbors, double tolerance, int max_iterations, double sheet,
                             py::object progress) {
    const Points x = to_points(points), s = to_points(onto);
    const OptionalPoints given(onto_normals);
    MlsOptions o = mls_options(neighbors, tolerance, max_iterations);
    o.sheet = sheet;
    PythonProgress pp(progress);
    if (given.present) o.support_normals = &given.p;
    else o.thin_sheets = true;
    MlsResult r = without_gil([&] {
      const SpatialIndex index(s);
      const Eigen::VectorXd h = kernel * local_spacing(index, 6);
      return mls_project(x, index, h, o, ProgressStage{pp.get(), 0.0, 1.0});
    });
    return py::make_tuple(r.positions, r.normals, r.not_converged, r.degenerate);
  });

  m.def("shoot_rays", [](const DoubleArray& origins, const DoubleArray& directions, const DoubleArray& onto,
                         double kernel, int neighbors, double tolerance, int max_iterations, double max_distance,
                         double min_cosine) {
    const Points o = to_points(origins), d = to_points(directions), s = to_points(onto);
    RayOptions ro;
    ro.neighbors = neighbors;
    ro.tolerance = tolerance;
    ro.max_iterations = max_iterations;
    ro.max_distance = max_distance;
    ro.min_cosine = min_cosine;
    RayHits r = without_gil([&] {
      const SpatialIndex index(s);
      return shoot_rays(o, d, index, kernel * local_spacing(index, 6), ro);
    });
    py::array_t<bool> missed(static_cast<py::ssize_t>(r.missed.size()));
    std::copy(r.missed.begin(), r.missed.end(), missed.mutable_data());
    return py::make_tuple(r.positions, r.distances, missed);
  });

  m.def("encode", [](const DoubleArray& points, const DoubleArray& base, py::object base_normals, double kernel,
                     int neighbors, double tolerance, int max_iterations, double max_variation, py::object progress) {
    const Points p = to_points(points), b = to_points(base);
    const OptionalPoints bn(base_normals);
    EncodeOptions o;
    o.kernel = kernel;
    o.mls = mls_options(neighbors, tolerance, max_iterations);
    o.max_variation = max_variation;
    PythonProgress pp(progress);
    return without_gil([&] { return encode_onto(p, b, bn.get(), o, pp.get()); });
  });

  m.def("morph", [](const DoubleArray& a, const DoubleArray& b, const DoubleArray& base, py::object base_normals,
                    double kernel, int neighbors, double tolerance, int max_iterations, int interpolation_neighbors,
                    py::object progress) {
    const Points pa = to_points(a), pb = to_points(b), ps = to_points(base);
    const OptionalPoints bn(base_normals);
    MorphOptions o;
    o.kernel = kernel;
    o.mls = mls_options(neighbors, tolerance, max_iterations);
    o.interpolation_neighbors = interpolation_neighbors;
    PythonProgress pp(progress);
    MorphModel r = without_gil([&] { return morph(pa, pb, ps, bn.get(), o, pp.get()); });
    py::dict d;
    d["base"] = r.base;
    d["normals"] = r.normals;
    d["detail_a"] = r.detail_a;
    d["detail_b"] = r.detail_b;
    d["not_converged"] = r.not_converged;
    d["degenerate"] = r.degenerate;
    return d;
  });

  m.def("knn_interpolate", [](const DoubleArray& from, const Eigen::VectorXd& values, const DoubleArray& to, int k) {
    const Points f = to_points(from), t = to_points(to);
    return without_gil([&] { return knn_interpolate(f, values, t, k); });
  });

  m.def("decompose_rayshoot", [](const DoubleArray& points, py::object normals, int levels, double decimation,
                                 double kernel, int neighbors, double tolerance, int max_iterations,
                                 double max_variation, py::object diffusion, double max_distance, double fine_kernel,
                                 py::object progress) {
    const Points p = to_points(points);
    const OptionalPoints n(normals);
    DecomposeOptions o;
    o.levels = levels;
    o.decimation = decimation;
    o.kernel = kernel;
    o.max_variation = max_variation;
    o.mls = mls_options(neighbors, tolerance, max_iterations);
    DiffusionOptions dif;
    const bool diffused = !diffusion.is_none();
    if (diffused) {
      auto t = diffusion.cast<py::tuple>();  // (neighbors, lambda, mu, iterations)
      dif.neighbors = t[0].cast<int>();
      dif.lambda = t[1].cast<double>();
      dif.mu = t[2].cast<double>();
      dif.iterations = t[3].cast<int>();
    }
    RayOptions rays;
    rays.neighbors = neighbors;
    rays.max_iterations = std::max(max_iterations, 50);
    rays.max_distance = max_distance;
    RayshootReport report;
    PythonProgress pp(progress);
    MultiscaleModel model = without_gil([&] {
      return decompose_rayshoot(p, n.get(), o, diffused ? &dif : nullptr, rays, fine_kernel, report, pp.get());
    });
    py::list missed;
    for (const auto& v : report.missed_points) missed.append(index_array(v));
    return py::make_tuple(std::move(model), missed);
  });
}
