#include "pointscale/level_support.h"

#include <algorithm>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>
#include <limits>
#include <numeric>

#if defined(_M_X64) && !defined(__GNUC__)
#include <xmmintrin.h>  // _mm_prefetch (MSVC)
#endif

#include "pointscale/detail/batched_eigen.h"
#include "pointscale/parallel.h"
#include "pointscale/detail/plane_fit.h"
#include "pointscale/spatial_order.h"
#include "pointscale/detail/stencil_plane.h"
#include "pointscale/detail/cluster_layout.h"
#include "pointscale/detail/level_normals.h"

namespace pointscale {

void support_centroids(const Points& level, const LevelSupport& support, Points& out) {
  out.resize(support.clusters, 3);
  for (Index c = 0; c < support.clusters; ++c) out.row(c) = level.row(support.anchors[c]);
}

Points support_centroids(const Points& level, const LevelSupport& support) {
  Points out;
  support_centroids(level, support, out);
  return out;
}

void choose_anchors(const Points& fine, const Points& level, LevelSupport& support, const Index* rank) {
  support.anchors.assign(static_cast<std::size_t>(support.clusters), -1);
  std::vector<double> best(static_cast<std::size_t>(support.clusters), std::numeric_limits<double>::infinity());
  for (Eigen::Index i = 0; i < level.rows(); ++i) {
    const Index c = support.labels[i];
    const double d = (fine.row(i) - level.row(i)).squaredNorm();
    const Index a = support.anchors[c];
    if (d < best[c] || (rank && a >= 0 && d == best[c] && rank[i] < rank[a])) { best[c] = d; support.anchors[c] = static_cast<Index>(i); }
  }
}

namespace {

// Asks for the cache line at p ahead of its use. An asm statement, because GCC -O3 dropped
// __builtin_prefetch from this loop (the loop has no other effect); MSVC has no GNU asm on x64
// but keeps its intrinsic. Elsewhere (arm64) a no-op: only speed is at stake.
inline void prefetch_line(const void* p) {
#if defined(__x86_64__) && defined(__GNUC__)
  asm volatile("prefetcht0 %0" : : "m"(*static_cast<const char*>(p)));
#elif defined(_M_X64)
  _mm_prefetch(static_cast<const char*>(p), _MM_HINT_T0);
#else
  (void)p;
#endif
}

// support_normals with the queries of each cluster given by
// fill_queries(c, t, members, m, queries): the m queries members[0..m) of cluster c (t: the
// place of the first in the grouping by cluster) as positions relative to the centroid of c,
// written to queries (#m by 3), so that callers that can compute them on the fly need not
// hold all of them (#Q by 3 doubles) at once, and can work out per cluster what its queries
// share (its frame). Works cluster by cluster: all members of a cluster are fitted to the
// same neighbour clusters, gathered once.
// point_rows: rows that fill_queries reads by query index, to prefetch; null if it reads none.
// cached_groups: the queries grouped by query_labels (cluster_layout.h, or any grouping with the same
// groups), if the caller has them already.
// only: if given, the clusters to work on (the others are skipped without a look), and
// cached_groups, required then, groups the queries by place in that list.
// Writes into `normals`, whose storage is reused when it has n rows already (reconstruction
// alternates two buffers: fresh pages cost it more than the copies it saves).
template <class FillQueries>
void normals_at(Eigen::Index n, const Points* point_rows, const FillQueries& fill_queries, const Index* query_labels,
                const Points& centroids, const LevelSupport& support, const Points& reference,
                const ProgressStage& stage, Points& normals, const LabelGroups* cached_groups = nullptr,
                const IndexList* only = nullptr) {
  const int k = support.neighbors;
  const bool has_reference = reference.rows() > 0;
  // Weights floored (plane_fit.h): the normal must be a smooth function of the anchors, since
  // reconstruction re-evaluates it, also at outliers far from them.
  const LabelGroups own = cached_groups ? LabelGroups()
                                        : group_by_label(query_labels, static_cast<std::size_t>(n), support.clusters);
  const LabelGroups& groups = cached_groups ? *cached_groups : own;
  normals.resize(n, 3);
  // The clusters worked on: all, or the listed ones, whose groups are then by place in the list.
  const std::size_t clusters = only ? only->size() : static_cast<std::size_t>(support.clusters);
  const std::size_t chunk = std::max<std::size_t>(1, 512 * clusters / std::max<std::size_t>(1, n));
  parallel_for(clusters, [&](std::size_t b, std::size_t e) {
    PlaneStencil stencil;
    std::vector<double> queries, cov, trace, valid;
    std::vector<double> w(k, 1.0);
    // Covariances wait here, from any cluster, until sixteen fill one batched eigen solve.
    struct Pending {
      alignas(64) double cov[6][eigen_lanes], trace[eigen_lanes], used[eigen_lanes];
      Eigen::Index row[eigen_lanes];
      Index cluster[eigen_lanes];
      Vec3 query[eigen_lanes];
      int count = 0;
    } pending;
    auto flush = [&]() {
      for (int l = pending.count; l < eigen_lanes; ++l) pending.used[l] = 0.0;
      alignas(64) double solved[3][eigen_lanes], ok[eigen_lanes];
      solve_eigen_batch(pending.cov, pending.trace, pending.used, solved, ok);
      for (int l = 0; l < pending.count; ++l) {
        const Eigen::Index i = pending.row[l];
        Vec3 nrm = Vec3::UnitZ();
        if (ok[l] != 0.0) {
          nrm = Vec3(solved[0][l], solved[1][l], solved[2][l]);
        } else {
          // No plane with the Gaussian weights: fall back on uniform ones. Never on the
          // reference's direction, which differs between the passes.
          const Index c = pending.cluster[l];
          const Index* nb = support.neighborhoods.data() + static_cast<std::size_t>(c) * k;
          const Vec3 x = centroids.row(c).transpose() + pending.query[l];
          const PlaneFit fit = fit_weighted_plane(centroids, nb, w.data(), k, x);
          if (fit.ok) nrm = fit.normal;
        }
        if (has_reference) {
          if (nrm.dot(reference.row(i).transpose()) < 0.0) nrm = -nrm;
        }
        normals.row(i) = nrm.transpose();
      }
      pending.count = 0;
    };
    // A cluster's members lie anywhere in the point order, so this loop would wait on memory
    // for their rows: fetch the rows of the cluster three ahead while this one works.
    auto prefetch = [&](std::size_t cc) {
      if (cc >= clusters) return;
      for (Index t = groups.offsets[cc]; t < groups.offsets[cc + 1]; ++t) {
        const Eigen::Index i = groups.members[static_cast<std::size_t>(t)];
        if (point_rows) prefetch_line(point_rows->data() + 3 * i);
        prefetch_line(normals.data() + 3 * i);
        if (has_reference) prefetch_line(reference.data() + 3 * i);
      }
    };
    for (std::size_t a = b; a < b + 3; ++a) prefetch(a);
    for (std::size_t t = b; t < e; ++t) {
      prefetch(t + 3);
      const Index c = only ? (*only)[t] : static_cast<Index>(t);
      const Index* members = groups.members.data() + groups.offsets[t];
      const int m = groups.offsets[t + 1] - groups.offsets[t];
      if (m == 0) continue;
      const Index* nb = support.neighborhoods.data() + static_cast<std::size_t>(c) * k;
      stencil.assign(centroids, nb, k, support.h, centroids.row(c).transpose());
      const auto mm = static_cast<std::size_t>(m);
      queries.resize(3 * mm); cov.resize(6 * mm); trace.resize(mm); valid.resize(mm);
      fill_queries(c, groups.offsets[t], members, m, queries.data());
      stencil_covariances(stencil, queries.data(), m, weight_floor, cov.data(), trace.data(), valid.data());
      for (int t = 0; t < m; ++t) {
        const int l = pending.count++;
        const bool plane = valid[t] != 0.0;
        // A lane without a plane holds a harmless one, and the fallback runs for it.
        for (int j = 0; j < 6; ++j) pending.cov[j][l] = plane ? cov[6 * t + j] : (j == 1 || j == 2 ? 1.0 : 0.0);
        pending.trace[l] = plane ? trace[t] : 2.0;
        pending.used[l] = plane ? 1.0 : 0.0;
        pending.row[l] = members[t];
        pending.cluster[l] = c;
        pending.query[l] = Vec3(queries[3 * t], queries[3 * t + 1], queries[3 * t + 2]);
        if (pending.count == eigen_lanes) flush();
      }
    }
    if (pending.count > 0) flush();
  }, stage, chunk);
}

// fill_queries for queries given as positions (#Q by 3): each relative to its cluster's centroid.
auto relative_to_centroid(const Points& query, const Points& centroids) {
  return [&query, &centroids](Index c, Index, const Index* members, int m, double* q) {
    for (int t = 0; t < m; ++t)
      for (int a = 0; a < 3; ++a) q[3 * t + a] = query(members[t], a) - centroids(c, a);
  };
}

}  // namespace

Points support_normals_of(const Points& query, const IndexList& clusters, const Points& centroids,
                          const LevelSupport& support, const Points& reference, const ProgressStage& stage) {
  Points normals;
  // One query per listed cluster: group t is query t alone.
  LabelGroups groups;
  groups.offsets.resize(clusters.size() + 1);
  groups.members.resize(clusters.size());
  std::iota(groups.offsets.begin(), groups.offsets.end(), 0);
  std::iota(groups.members.begin(), groups.members.end(), 0);
  normals_at(query.rows(), &query, relative_to_centroid(query, centroids), clusters.data(), centroids, support,
             reference, stage, normals, &groups, &clusters);
  return normals;
}

Points support_normals(const Points& query, const Index* query_labels, const Points& centroids,
                       const LevelSupport& support, const Points& reference, const ProgressStage& stage) {
  Points normals;
  normals_at(query.rows(), &query, relative_to_centroid(query, centroids), query_labels, centroids, support,
             reference, stage, normals);
  return normals;
}

namespace {

// Orthonormal frame of cluster c: origin, then columns t1, t2, t1 x t2.
Mat3 cluster_frame(const Points& centroids, const LevelSupport& support, Index c) {
  const Index a = support.frames[2 * static_cast<std::size_t>(c)];
  const Index b = support.frames[2 * static_cast<std::size_t>(c) + 1];
  const Vec3 o = centroids.row(c).transpose();
  Vec3 t1 = centroids.row(a).transpose() - o;
  Vec3 t2 = centroids.row(b).transpose() - o;
  if (a == c || b == c || !(t1.norm() > 0)) return Mat3::Identity();
  t1.normalize();
  t2 -= t2.dot(t1) * t1;
  if (!(t2.norm() > 1e-12 * (centroids.row(b).transpose() - o).norm())) return Mat3::Identity();
  t2.normalize();
  Mat3 f;
  f << t1, t2, t1.cross(t2);
  return f;
}

}  // namespace

void attach_frames(const Points& centroids, const Points& positions, LevelSupport& support,
                   const LabelGroups* groups) {
  const int k = support.neighbors;
  support.frames.assign(2 * static_cast<std::size_t>(support.clusters), 0);
  for (Index c = 0; c < support.clusters; ++c) {
    const Index* nb = support.neighborhoods.data() + static_cast<std::size_t>(c) * k;
    const Vec3 o = centroids.row(c).transpose();
    Index a = c, b = c;
    Vec3 t1 = Vec3::Zero();
    for (int j = 1; j < k && a == c; ++j) {
      const Vec3 e = centroids.row(nb[j]).transpose() - o;
      if (e.norm() > 0) { a = nb[j]; t1 = e.normalized(); }
    }
    double best = 0.0;
    for (int j = 1; j < k && a != c; ++j) {
      const Vec3 e = centroids.row(nb[j]).transpose() - o;
      const double len = e.norm();
      if (!(len > 0) || nb[j] == a) continue;
      const double ortho = (e - e.dot(t1) * t1).norm() / len;  // sine of the angle to t1
      if (ortho > best + 1e-9) { best = ortho; b = nb[j]; }
      if (best > 0.7) break;  // well spread: keep the nearest such neighbour
    }
    support.frames[2 * static_cast<std::size_t>(c)] = a;
    support.frames[2 * static_cast<std::size_t>(c) + 1] = b;
  }
  // In the layout of cluster_layout.h: row t for point members[t].
  const LabelGroups own = groups ? LabelGroups() : cluster_layout(support.labels, support.clusters);
  const LabelGroups& g = groups ? *groups : own;
  support.local.resize(positions.rows(), 3);
  parallel_for(static_cast<std::size_t>(support.clusters), [&](std::size_t b, std::size_t e) {
    for (std::size_t cc = b; cc < e; ++cc) {
      const Index c = static_cast<Index>(cc);
      const Mat3 f = cluster_frame(centroids, support, c);
      for (Index t = g.offsets[cc]; t < g.offsets[cc + 1]; ++t) {
        const Eigen::Index i = g.members[static_cast<std::size_t>(t)];
        support.local.row(t) = (f.transpose() * (positions.row(i) - centroids.row(c)).transpose()).transpose();
      }
    }
  }, {}, 256);
}

Points local_by_point(const LevelSupport& support) {
  const LabelGroups groups = cluster_layout(support.labels, support.clusters);
  Points out(support.local.rows(), 3);
  for (std::size_t t = 0; t < groups.members.size(); ++t)
    out.row(groups.members[t]) = support.local.row(static_cast<Eigen::Index>(t));
  return out;
}

void local_from_points(const Points& by_point, LevelSupport& support) {
  const LabelGroups groups = cluster_layout(support.labels, support.clusters);
  support.local.resize(by_point.rows(), 3);
  for (std::size_t t = 0; t < groups.members.size(); ++t)
    support.local.row(static_cast<Eigen::Index>(t)) = by_point.row(groups.members[t]);
}

namespace {

// The queries of cluster c from their frame coordinates (rows row_of(t) of support.local),
// turned into the cluster's frame, worked out once per cluster.
template <class RowOf>
void frame_queries(const Points& centroids, const LevelSupport& support, Index c, int m, const RowOf& row_of,
                   double* q) {
  const Mat3 f = cluster_frame(centroids, support, c);
  for (int t = 0; t < m; ++t) {
    const Vec3 v = f * support.local.row(row_of(t)).transpose();
    q[3 * t] = v.x(); q[3 * t + 1] = v.y(); q[3 * t + 2] = v.z();
  }
}

void anchor_normals_into(const Points& centroids, const LevelSupport& support, const Points& reference,
                         const ProgressStage& stage, Points& normals, const LabelGroups* groups = nullptr) {
  // The grouping is the one support.local is stored in, so row t is the query's own.
  normals_at(support.local.rows(), nullptr,
             [&](Index c, Index first, const Index*, int m, double* q) {
               frame_queries(centroids, support, c, m, [&](int t) { return first + t; }, q);
             },
             support.labels.data(), centroids, support, reference, stage, normals, groups);
}

}  // namespace

Points level_normals(const Points& level, const LevelSupport& support, const Points& reference,
                     const ProgressStage& stage) {
  Points normals;
  level_normals(level, support, reference, stage, normals);
  return normals;
}

void level_normals(const Points& level, const LevelSupport& support, const Points& reference,
                   const ProgressStage& stage, Points& normals, const LabelGroups* groups, Points* centroids) {
  Points own;
  Points& anchors = centroids ? *centroids : own;
  support_centroids(level, support, anchors);
  anchor_normals_into(anchors, support, reference, stage, normals, groups);
}

Points anchor_normals_of_clusters(const Points& centroids, const LevelSupport& support,
                                  const std::vector<unsigned char>& clusters, IndexList& which,
                                  const IndexList* rank) {
  // Taken cluster by cluster in the order support.local is stored in: rows[j] is which[j]'s row.
  // Only the flagged clusters' points are listed (no grouping of all the points is made).
  const std::size_t n = support.labels.size();
  std::vector<Index> first(static_cast<std::size_t>(support.clusters) + 1, 0);  // each cluster's first row
  for (Index c : support.labels) ++first[static_cast<std::size_t>(c) + 1];
  for (std::size_t c = 0; c < static_cast<std::size_t>(support.clusters); ++c) first[c + 1] += first[c];
  which.clear();
  for (std::size_t i = 0; i < n; ++i)
    if (clusters[support.labels[i]]) which.push_back(static_cast<Index>(i));
  // By cluster, then in layout order within it: index order, or rank order when given.
  std::stable_sort(which.begin(), which.end(), [&](Index a, Index b) {
    const Index ca = support.labels[a], cb = support.labels[b];
    if (ca != cb) return ca < cb;
    return rank ? (*rank)[a] < (*rank)[b] : a < b;
  });
  IndexList rows(which.size()), labels(which.size());
  for (std::size_t j = 0; j < which.size(); ++j) {
    const Index c = support.labels[which[j]];
    labels[j] = c;
    rows[j] = j > 0 && labels[j - 1] == c ? rows[j - 1] + 1 : first[c];
  }
  Points normals;
  normals_at(static_cast<Eigen::Index>(which.size()), nullptr,
             [&](Index c, Index, const Index* members, int m, double* q) {
               frame_queries(centroids, support, c, m, [&](int t) { return rows[members[t]]; }, q);
             },
             labels.data(), centroids, support, Points(), {}, normals);
  return normals;
}

}  // namespace pointscale
