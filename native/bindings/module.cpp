// pybind11 bindings of the core's model: decompose, reconstruct, folds, projection, normals and
// the loading of saved models (operators.cpp binds the further operators). Every long call
// releases the GIL, with the thread count asked for that call; the progress callback takes the
// GIL back only for the moment it runs.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <mutex>

#include "pointscale/cluster_decimation.h"
#include "pointscale/connected_parts.h"
#include "pointscale/decomposition.h"
#include "pointscale/folds.h"
#include "pointscale/mls_projection.h"
#include "pointscale/single_pass.h"
#include "pointscale/normal_estimation.h"
#include "pointscale/oriented_normals.h"
#include "pointscale/reconstruction.h"
#include "pointscale/reconstructor.h"
#include "pointscale/sample_spacing.h"
#include "pointscale/spatial_order.h"
#include "pointscale/stored_base.h"
#include "pointscale/validation.h"
#include "bindings.h"

namespace py = pybind11;
using namespace pointscale;
using namespace pointscale_bindings;

namespace {

// Gains (k,) per band or (k, n) per point as a k by 1 or k by n matrix.
Eigen::MatrixXd to_gains(const DoubleArray& gains) {
  if (gains.ndim() < 1 || gains.ndim() > 2) throw std::invalid_argument("gains must be (k,) or (k, n)");
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      gains.data(), gains.shape(0), gains.ndim() == 2 ? gains.shape(1) : 1);
}

py::dict report_dict(const LevelReport& r) {
  py::dict d;
  d["support_points"] = r.support_points;
  d["kernel_width"] = r.kernel_width;
  d["not_converged"] = r.not_converged;
  d["degenerate"] = r.degenerate;
  d["consistency_iterations"] = r.consistency_iterations;
  d["consistency_residual"] = r.consistency_residual;
  d["pinned"] = r.pinned;
  return d;
}

py::dict model_arrays(const MultiscaleModel& m) {
  py::dict d;
  const int k = m.bands();
  const py::ssize_t n = m.base.rows();
  d["base"] = m.base;
  d["details"] = Eigen::MatrixXd(m.details);
  d["base_normals"] = m.base_normals;
  py::array_t<Index> labels({static_cast<py::ssize_t>(k), n});
  for (int l = 0; l < k; ++l) {
    std::copy(m.support[l].labels.begin(), m.support[l].labels.end(), labels.mutable_data(l, 0));
    const std::string s = std::to_string(l);
    d[("neighborhoods_" + s).c_str()] =
        to_array(m.support[l].neighborhoods, {m.support[l].clusters, m.support[l].neighbors});
    d[("kernel_" + s).c_str()] = Eigen::VectorXd(m.support[l].h);
    d[("anchors_" + s).c_str()] = to_array(m.support[l].anchors, {m.support[l].clusters});
    d[("frames_" + s).c_str()] = to_array(m.support[l].frames, {m.support[l].clusters, 2});
    d[("local_" + s).c_str()] = local_by_point(m.support[l]);  // saved in point order
  }
  d["labels"] = labels;
  if (!m.parts.empty()) d["parts"] = to_array(m.parts, {n});
  return d;
}

// A saved model's arrays as the core's model. Only their shapes are checked here, as they are
// read; validate(model) (validation.h) then checks the values, so that a damaged or hand-made
// file raises ValueError (std::invalid_argument) instead of reading out of bounds or giving NaN.
// The pointscale package checks the file's arrays first, by their keys (multiscale.py).
py::object item(const py::dict& d, const std::string& key) {
  if (!d.contains(key.c_str())) throw std::invalid_argument("not a valid decomposition: missing array " + key);
  return d[key.c_str()];
}

void require_shape(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

MultiscaleModel model_from_arrays(const py::dict& d) {
  MultiscaleModel m;
  m.base = to_points(item(d, "base").cast<DoubleArray>());
  const Eigen::Index n = m.base.rows();
  auto details = item(d, "details").cast<DoubleArray>();
  require_shape(details.ndim() == 2 && details.shape(1) == n, "details must be (k, n)");
  const int k = static_cast<int>(details.shape(0));
  m.details = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      details.data(), k, n);
  m.base_normals = to_points(item(d, "base_normals").cast<DoubleArray>());
  auto labels = item(d, "labels").cast<IndexArray>();
  require_shape(labels.ndim() == 2 && labels.shape(0) == k && labels.shape(1) == n, "labels must be (k, n)");
  m.support.resize(k);
  m.reports.resize(k);
  for (int l = 0; l < k; ++l) {
    const std::string s = std::to_string(l);
    LevelSupport& sup = m.support[l];
    auto nb = item(d, "neighborhoods_" + s).cast<IndexArray>();
    auto h = item(d, "kernel_" + s).cast<DoubleArray>();
    require_shape(nb.ndim() == 2 && h.ndim() == 1 && h.shape(0) == nb.shape(0), "inconsistent support arrays at level " + s);
    sup.clusters = static_cast<Index>(nb.shape(0));
    sup.neighbors = static_cast<int>(nb.shape(1));
    sup.neighborhoods.assign(nb.data(), nb.data() + nb.size());
    sup.labels.assign(labels.data(l, 0), labels.data(l, 0) + n);
    sup.h = Eigen::Map<const Eigen::VectorXd>(h.data(), h.shape(0));
    auto an = item(d, "anchors_" + s).cast<IndexArray>();
    require_shape(an.ndim() == 1 && an.shape(0) == sup.clusters, "anchors must be (clusters,) at level " + s);
    sup.anchors.assign(an.data(), an.data() + an.size());
    auto fr = item(d, "frames_" + s).cast<IndexArray>();
    require_shape(fr.ndim() == 2 && fr.shape(0) == sup.clusters && fr.shape(1) == 2, "frames must be (clusters, 2) at level " + s);
    sup.frames.assign(fr.data(), fr.data() + fr.size());
    sup.local = to_points(item(d, "local_" + s).cast<DoubleArray>());  // in point order until checked
  }
  if (d.contains("parts")) {
    auto parts = d["parts"].cast<IndexArray>();
    require_shape(parts.ndim() == 1 && parts.shape(0) == n, "parts must be (n,)");
    m.parts.assign(parts.data(), parts.data() + n);
  }
  validate(m);
  // Saved in point order; the core keeps them in cluster order (level_support.h), which the
  // labels, now checked, give.
  for (LevelSupport& sup : m.support) {
    const Points by_point = std::move(sup.local);
    local_from_points(by_point, sup);
  }
  return m;
}

}  // namespace

void bind_options(py::module_& m);    // options.cpp
void bind_operators(py::module_& m);  // operators.cpp
void bind_validation(py::module_& m);  // validation.cpp

PYBIND11_MODULE(_core, m) {
  m.doc() = "Pointscale native core. Use the pointscale package instead of this module.";
  py::register_exception<Cancelled>(m, "Cancelled");
  bind_options(m);  // first: the functions below take these classes

  py::class_<MultiscaleModel>(m, "Model")
      .def_property_readonly("base", [](const MultiscaleModel& s) { return s.base; })
      .def_property_readonly("details", [](const MultiscaleModel& s) { return Eigen::MatrixXd(s.details); })
      .def_property_readonly("base_normals", [](const MultiscaleModel& s) { return s.base_normals; })
      .def_property_readonly("bands", &MultiscaleModel::bands)
      // Read in place: copying the base and the detail out to test them would add their size
      // to the peak of the decompose that has just built them.
      .def_property_readonly("base_finite", [](const MultiscaleModel& s) { return s.base.allFinite(); })
      .def_property_readonly("details_finite", [](const MultiscaleModel& s) { return s.details.allFinite(); })
      .def_property_readonly("points", [](const MultiscaleModel& s) { return s.base.rows(); })
      .def_property_readonly("parts", [](const MultiscaleModel& s) -> py::object {
        if (s.parts.empty()) return py::none();
        return to_array(s.parts);
      })
      .def_property_readonly("reports", [](const MultiscaleModel& s) {
        py::list out;
        for (const auto& r : s.reports) out.append(report_dict(r));
        return out;
      })
      .def("to_arrays", &model_arrays)
      .def_static("from_arrays", &model_from_arrays)
      // origin: the decomposition's origin, or None. Given, `base` comes in world coordinates
      // and the points go out in them (one pass each way fewer than doing it in NumPy).
      // memo: the decomposition's EditMemo, or None (reconstruction.h).
      .def("reconstruct", [](const MultiscaleModel& s, const DoubleArray& gains, py::object base, bool keep_levels,
                             int upto, py::object progress, py::object origin, int threads, py::object memo) {
        const Eigen::MatrixXd g = to_gains(gains);  // checked by the core (validation.h)
        Points edited;
        bool has_base = !base.is_none();
        const Vec3 o = to_origin(origin);
        if (has_base) {
          const DoubleArray b = base.cast<DoubleArray>();
          // The stored base handed back in world coordinates (base + origin, as the package
          // gives it) is the stored base: centring it again would round it off it, and an
          // edit of no size would cost a whole edited pass.
          has_base = origin.is_none() || b.ndim() != 2 || b.shape(0) != s.base.rows() || b.shape(1) != 3 ||
                     !is_stored_base(b.data(), s.base, o);
          if (has_base) edited = to_points_centred(b, o);
        }
        EditMemo* kept = memo.is_none() ? nullptr : &memo.cast<EditMemo&>();
        PythonProgress p(progress);
        Reconstruction r = without_gil(threads, [&] {
          Reconstruction out = has_base ? reconstruct_from_base(s, g, std::move(edited), keep_levels, upto, p.get(), kept)
                                        : reconstruct(s, g, nullptr, keep_levels, upto, p.get(), kept);
          if (!origin.is_none()) {
            out.positions.rowwise() += o.transpose();
            for (Points& level : out.levels) level.rowwise() += o.transpose();
          }
          return out;
        });
        if (!keep_levels) return py::object(py::cast(std::move(r.positions)));
        // Each array moved into its NumPy owner, not copied: 2k + 1 arrays of n x 3, which would
        // cost about as much to copy as to compute.
        py::list levels, normals;
        for (Points& level : r.levels) levels.append(py::cast(std::move(level)));
        for (Points& level_normals : r.normals) normals.append(py::cast(std::move(level_normals)));
        return py::object(py::make_tuple(levels, normals));
      }, py::arg("gains"), py::arg("base") = py::none(), py::arg("keep_levels") = false, py::arg("upto") = -1,
         py::arg("progress") = py::none(), py::arg("origin") = py::none(), py::arg("threads") = 0,
         py::arg("memo") = py::none());

  // What a model's stateless reconstructions on an edited base share (reconstruction.h).
  py::class_<EditMemo>(m, "EditMemo").def(py::init<>());

  // The solver for repeated reconstructions (reconstructor.h), which checks its arguments.
  py::class_<Reconstructor>(m, "Reconstructor")
      .def(py::init([](const MultiscaleModel& model, int threads) {
        return without_gil(threads, [&] { return std::make_unique<Reconstructor>(model); });
      }), py::arg("model"), py::arg("threads") = 0)
      .def("reconstruct", [](Reconstructor& r, const DoubleArray& gains, py::object base, py::object progress,
                             py::object origin, int threads) {
        const Eigen::Index n = r.points();
        const Eigen::MatrixXd g = to_gains(gains);
        const Vec3 o = to_origin(origin);
        DoubleArray b;
        if (!base.is_none()) {
          b = base.cast<DoubleArray>();
          if (b.ndim() != 2 || b.shape(1) != 3) throw std::invalid_argument("base must be an (n, 3) array");
          // The core takes the rows by pointer, so it cannot see their count: checked here (the
          // rest of the base the core checks).
          check_rows(b.shape(0), n, "base");
        }
        const double* base_rows = base.is_none() ? nullptr : b.data();
        PythonProgress p(progress);
        return without_gil(threads, [&] { return r.reconstruct(g, base_rows, o, p.get()); });
      }, py::arg("gains"), py::arg("base") = py::none(), py::arg("progress") = py::none(),
         py::arg("origin") = py::none(), py::arg("threads") = 0);

  // Folds of a result over its base (folds.h). result and base come in the package's world
  // coordinates; origin is the decomposition's (the stored base is model.base + origin).
  py::class_<FoldReference>(m, "FoldReference", "What a model's folds are measured against (folds.h).")
      .def_property_readonly("rings", [](const FoldReference& r) {
        // Point by point, as point indices (the reference keeps them by slot).
        const std::size_t n = r.other_sheet.size(), w = static_cast<std::size_t>(r.ring_size);
        IndexList rings(n * w);
        for (std::size_t i = 0; i < n; ++i)
          for (std::size_t m = 0; m < w; ++m)
            rings[i * w + m] = r.order[static_cast<std::size_t>(r.rings[static_cast<std::size_t>(r.slot[i]) * w + m])];
        return to_array(rings, {static_cast<py::ssize_t>(n), r.ring_size});
      });
  m.def("fold_reference", [](const MultiscaleModel& s, py::object input, py::object base, py::object base_normals,
                              int threads) {
    const OptionalPoints in(input), b(base), bn(base_normals);
    return without_gil(threads, [&] { return fold_reference(s, in.get(), b.get(), bn.get()); });
  }, py::arg("model"), py::arg("input") = py::none(), py::arg("base") = py::none(),
     py::arg("base_normals") = py::none(), py::arg("threads") = 0);

  m.def("find_folds", [](const MultiscaleModel& s, const FoldReference& ref, const DoubleArray& result,
                         py::object base, int threads) {
    if (result.ndim() != 2 || result.shape(1) != 3) throw std::invalid_argument("result must be an (n, 3) array");
    const OptionalPoints edited(base);
    const Eigen::Map<const Points> r(result.data(), result.shape(0), 3);  // find_folds checks the rest
    std::vector<std::uint8_t> kind;
    without_gil(threads, [&] { find_folds(s, ref, edited.get(), r, kind); });
    return to_array(kind, {static_cast<py::ssize_t>(kind.size())});
  }, py::arg("model"), py::arg("reference"), py::arg("result"), py::arg("base") = py::none(),
     py::arg("threads") = 0);

  // Limits the gain where the result folds, in place on `result` (a writable C-contiguous
  // float64 (n, 3) array); returns what limit_folds reports.
  m.def("limit_folds", [](const MultiscaleModel& s, const FoldReference& ref,
                          py::array_t<double, py::array::c_style> result, py::object base, py::object origin,
                          int max_rounds, int smoothing, int threads) {
    if (!result.writeable() || result.ndim() != 2 || result.shape(1) != 3)
      throw std::invalid_argument("result must be a writable C-contiguous float64 (n, 3) array");
    const OptionalPoints edited(base);
    const Vec3 o = to_origin(origin);
    const Eigen::Index n = result.shape(0);  // limit_folds checks it and the rest
    Eigen::Map<Points> r(result.mutable_data(), n, 3);
    FoldLimitOptions options;
    options.max_rounds = max_rounds;
    options.smoothing = smoothing;
    FoldLimitReport rep = without_gil(threads, [&] { return limit_folds(s, ref, edited.get(), o, r, options); });
    const py::ssize_t count = static_cast<py::ssize_t>(n);
    py::dict d;
    d["before"] = to_array(rep.before, {count});
    d["after"] = to_array(rep.after, {count});
    d["limiter"] = rep.limiter.empty() ? py::object(py::none()) : py::object(to_array(rep.limiter, {count}));
    d["folded_before"] = rep.folded_before;
    d["folded_after"] = rep.folded_after;
    d["changed"] = rep.changed;
    d["rounds"] = rep.rounds;
    d["capped"] = rep.capped;
    return d;
  }, py::arg("model"), py::arg("reference"), py::arg("result"), py::arg("base") = py::none(),
     py::arg("origin") = py::none(), py::arg("max_rounds") = 40, py::arg("smoothing") = 2, py::arg("threads") = 0);

  // (labels, count) of the parts a mesh's connectivity joins; pairs (#E, 2) vertex indices.
  m.def("connected_parts", [](const DoubleArray& points, const IndexArray& pairs, int threads) {
    const Points p = to_points(points);
    if (pairs.ndim() != 2 || pairs.shape(1) != 2) throw py::value_error("pairs must be (m, 2)");
    const IndexList list(pairs.data(), pairs.data() + pairs.size());
    const Parts parts = without_gil(threads, [&] { return connected_parts(p, list); });
    return py::make_tuple(to_array(parts.labels), parts.count);
  }, py::arg("points"), py::arg("pairs"), py::arg("threads") = 0);

  // Every point's k nearest of its own part (itself first), #P by k; parts (#P,) labels.
  m.def("knn_within_parts", [](const DoubleArray& points, const IndexArray& parts, int k, int threads) {
    const Points p = to_points(points);
    if (parts.ndim() != 1) throw py::value_error("parts must be (n,)");
    const IndexList labels(parts.data(), parts.data() + parts.size());  // knn_within_parts checks them
    const IndexList rows = without_gil(threads, [&] { return knn_within_parts(p, labels, k); });
    return to_array(rows, {static_cast<py::ssize_t>(p.rows()), k});
  }, py::arg("points"), py::arg("parts"), py::arg("k"), py::arg("threads") = 0);

  // diffusion: the "diffusion" smoother's settings, or None for the MLS smoother.
  // estimate_sides (thin sheets without normals): the sides are the centred points' oriented
  // normals, as estimate_normals gives them, found here and handed to decompose, so that
  // nothing else holds them. Given normals are handed over too (decompose releases them once
  // it holds them in its own numbering); the caller's array is left as it is.
  m.def("decompose", [](const DoubleArray& points, const DoubleArray& origin, py::object normals,
                        DecomposeOptions options, const DiffusionOptions* diffusion, py::object progress,
                        int threads, bool estimate_sides) {
    Points p = to_points_centred(points, to_origin(origin));
    OptionalPoints n(normals);
    if (estimate_sides && (n.present || !options.thin_sheets))
      throw py::value_error("estimate_sides is for thin sheets without normals");
    options.thin_sheets = options.thin_sheets && (n.present || estimate_sides);
    options.diffusion = diffusion;
    PythonProgress pp(progress);
    return without_gil(threads, [&] {
      if (estimate_sides) {
        n.p = oriented_normals(Points(p), 16, orientation_width);
        if (!n.p.allFinite()) throw std::invalid_argument("the normals are not finite");
        n.present = true;
      }
      if (!n.present) return decompose(std::move(p), nullptr, options, pp.get());
      return decompose(std::move(p), std::move(n.p), options, pp.get());
    });
  }, py::arg("points"), py::arg("origin"), py::arg("normals"), py::arg("options"), py::arg("diffusion") = py::none(),
     py::arg("progress") = py::none(), py::arg("threads") = 0, py::arg("estimate_sides") = false);

  m.def("project", [](const DoubleArray& points, const DoubleArray& onto, double kernel, MlsOptions options,
                      py::object progress, py::object near, int threads) {
    Points x = to_points(points), s = to_points(onto);
    IndexList near_support, order;
    check_kernel(kernel);
    if (!near.is_none()) {
      const auto a = near.cast<IndexArray>();
      near_support.assign(a.data(), a.data() + a.size());
      check_near_support(near_support, x.rows(), s.rows());  // before group_by_label reads it
      order = group_by_label(near_support.data(), near_support.size(), static_cast<Index>(s.rows())).members;
      options.near_support = &near_support;
      options.order = &order;
    }
    PythonProgress pp(progress);
    MlsResult r = without_gil(threads, [&] {
      SpatialIndex index(s);
      const Eigen::VectorXd h = kernel * local_spacing(index, 6);
      return mls_project(x, index, h, options, ProgressStage{pp.get(), 0.0, 1.0});
    });
    return py::make_tuple(r.positions, r.normals, r.not_converged, r.degenerate);
  }, py::arg("points"), py::arg("onto"), py::arg("kernel"), py::arg("mls"), py::arg("progress") = py::none(),
     py::arg("near") = py::none(), py::arg("threads") = 0);

  // One plane fit and projection per point (single_pass.h). With self, the points are `onto`
  // itself (checked by the Python layer), so `points` is None and nothing is copied twice.
  m.def("project_single_pass", [](py::object points, const DoubleArray& onto, double kernel, int neighbors,
                                  bool self, bool estimate, py::object progress, int threads) {
    Points s = to_points(onto);
    Points x = self ? Points() : to_points(points.cast<DoubleArray>());
    PythonProgress pp(progress);
    SinglePassResult r = without_gil(threads, [&] {
      SpatialIndex index(s);
      return mls_single_pass(self ? index.points() : x, self, index, kernel, neighbors, estimate, ProgressStage{pp.get(), 0.0, 1.0});
    });
    return py::make_tuple(r.positions, r.normals, r.moved, r.next_step, r.degenerate);
  }, py::arg("points"), py::arg("onto"), py::arg("kernel"), py::arg("neighbors"), py::arg("self"),
     py::arg("estimate"), py::arg("progress") = py::none(), py::arg("threads") = 0);

  m.def("decimate", [](const DoubleArray& points, long long target, double max_variation, int threads) {
    Points p = to_points(points);
    check_decimation(p, target, max_variation);  // before target becomes a size
    Clustering c = without_gil(threads, [&] { return cluster_decimate(p, static_cast<std::size_t>(target), max_variation); });
    return py::make_tuple(c.centroids, to_array(c.labels));
  }, py::arg("points"), py::arg("target"), py::arg("max_variation"), py::arg("threads") = 0);

  m.def("estimate_normals", [](const DoubleArray& points, int neighbors, bool orient, int threads) {
    Points p = to_points(points);
    if (!orient) check_normal_estimation(p, neighbors);  // oriented_normals checks its own
    return without_gil(threads, [&] {
      // Fewer fit neighbours than the graph's width: the graph joins all of them (its width is at most k).
      if (orient) return oriented_normals(std::move(p), neighbors, std::min(neighbors, orientation_width));
      return pca_normals(SpatialIndex(std::move(p)), neighbors);
    });
  }, py::arg("points"), py::arg("neighbors"), py::arg("orient"), py::arg("threads") = 0);

  bind_operators(m);
  bind_validation(m);
}
