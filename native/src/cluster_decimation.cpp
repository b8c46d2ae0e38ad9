#include "pointscale/cluster_decimation.h"
#include "pointscale/validation.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <deque>
#include <memory>
#include <new>
#include <queue>

#include "pointscale/detail/thin_sheets.h"
#include "pointscale/parallel.h"

namespace pointscale {

namespace {

// One node of the split tree: a range of the working arrays, its centroid and its split axis.
struct Cluster {
  std::size_t begin, end;  // range in the working arrays
  Vec3 centroid;
  Vec3 axis;               // direction of largest covariance
  double priority;
  bool splittable;
  Cluster* child[2] = {nullptr, nullptr};  // filled once split
  // Thin sheets: the cluster holds both sides of a wall (its points' normals disagree), so it is
  // split by the side its points face, along side_axis, before anything else.
  bool by_side = false;
  Vec3 side_axis = Vec3::Zero();
};

// The input's coordinates and indices, reordered as clusters split, so that every pass over a
// cluster reads contiguous memory (through the input order, it would wait on memory).
struct Working {
  std::vector<double> xyz;  // 3 per point
  std::vector<Index> index;
  std::vector<double> nrm;  // 3 per point: oriented normals, when sheets are kept apart; else empty
  // Only a cluster of at most this many points is split by side (describe_sides): a larger one
  // spans enough of a curved surface that its normals disagree by curvature alone, and a split
  // by the way they face would join far pieces that face alike (the two ends of a closed
  // shell's diameter, one on each side), which the spatial splits after it need not part.
  // A larger cluster whose normals disagree is split through space first.
  std::size_t side_split_limit = 0;
};

// First and second moments about a reference point, the second as its six distinct entries.
struct Moments {
  double s[3] = {0, 0, 0};
  double ss[6] = {0, 0, 0, 0, 0, 0};  // xx xy xz yy yz zz
  inline void add(const double* x, const Vec3& ref) {
    const double dx = x[0] - ref.x(), dy = x[1] - ref.y(), dz = x[2] - ref.z();
    s[0] += dx; s[1] += dy; s[2] += dz;
    ss[0] += dx * dx; ss[1] += dx * dy; ss[2] += dx * dz;
    ss[3] += dy * dy; ss[4] += dy * dz; ss[5] += dz * dz;
  }
};

// The sum of a cluster's normals and of their outer products (about 0).
Moments normal_moments(const Working& w, std::size_t begin, std::size_t end) {
  Moments m;
  for (std::size_t i = begin; i < end; ++i) m.add(&w.nrm[3 * i], Vec3::Zero());
  return m;
}

// Below this length of its mean normal a cluster's points face different ways: the two sides of
// a thin wall average to about 0, while a one-sided patch keeps about 0.64 even when it turns
// through 180 degrees (a wall's rim) and 0.5 over a whole hemisphere.
constexpr double one_sided_agreement = 0.6;

// How many final clusters' worth of points a cluster split by side may hold (Working).
constexpr std::size_t side_split_sizes = 8;

// Whether a point faces the other way from its cluster's mean, by the projection's side test
// (same_side, thin_sheets.h). A cluster of a few points of one side and many of the other
// keeps a long mean, so the mean alone misses it; its centroid then stands for the wrong side
// in the other side's fits (on a hollow sphere one spacing thick, the sides crossed at level 0).
bool some_point_faces_away(const Working& w, std::size_t begin, std::size_t end, const Vec3& mean) {
  const Vec3 u = mean.normalized();
  for (std::size_t i = begin; i < end; ++i)
    if (!same_side(w.nrm[3 * i] * u.x() + w.nrm[3 * i + 1] * u.y() + w.nrm[3 * i + 2] * u.z())) return true;
  return false;
}

// A cluster whose normals disagree is split by the side they face: along the main axis of their
// outer products, the direction the two sides of a wall face, at first priority, since its
// centroid lies between the sides, off both.
void describe_sides(Cluster& c, const Working& w, std::size_t begin, std::size_t end) {
  const Moments normals = normal_moments(w, begin, end);
  const auto count = static_cast<double>(end - begin);
  const Vec3 mean(normals.s[0] / count, normals.s[1] / count, normals.s[2] / count);
  if (count < 2) return;
  if (!(mean.norm() < one_sided_agreement) && !some_point_faces_away(w, begin, end, mean)) return;
  if (end - begin > w.side_split_limit) {
    // Split through space first, so that no cluster left when the target is reached holds
    // both sides (its points are parted by side once there are few enough of them).
    c.priority = count * 1e6;
    return;
  }
  Mat3 ss;
  ss << normals.ss[0], normals.ss[1], normals.ss[2], normals.ss[1], normals.ss[3], normals.ss[4], normals.ss[2],
      normals.ss[4], normals.ss[5];
  Eigen::SelfAdjointEigenSolver<Mat3> eig;
  eig.computeDirect(ss / count);
  c.by_side = true;
  c.side_axis = eig.eigenvectors().col(2);
  c.splittable = true;
  c.priority = count * 1e6;
}

// Fills in a cluster from the first and second moments of its points about `ref`.
void describe(Cluster& c, const Vec3& ref, double count, const Moments& sums, double max_variation) {
  const Vec3 m = Vec3(sums.s[0], sums.s[1], sums.s[2]) / count;
  c.centroid = ref + m;
  Mat3 ss;
  ss << sums.ss[0], sums.ss[1], sums.ss[2], sums.ss[1], sums.ss[3], sums.ss[4], sums.ss[2], sums.ss[4], sums.ss[5];
  const Mat3 cov = ss / count - m * m.transpose();
  Eigen::SelfAdjointEigenSolver<Mat3> eig;
  eig.computeDirect(cov);
  const Vec3 ev = eig.eigenvalues();
  const double trace = ev.sum();
  c.axis = eig.eigenvectors().col(2);
  c.splittable = count > 1 && trace > 0.0;
  const double variation = trace > 0.0 ? std::max(0.0, ev(0)) / trace : 0.0;
  c.priority = count * (variation > max_variation ? 4.0 : 1.0);
}

Cluster whole(const Working& w, double max_variation) {
  const std::size_t n = w.index.size();
  Cluster c{0, n, Vec3::Zero(), Vec3::Zero(), 0.0, false};
  const Vec3 ref(w.xyz[0], w.xyz[1], w.xyz[2]);
  Moments sums;
  for (std::size_t i = 0; i < n; ++i) sums.add(&w.xyz[3 * i], ref);
  describe(c, ref, static_cast<double>(n), sums, max_variation);
  if (!w.nrm.empty()) describe_sides(c, w, 0, n);
  return c;
}

// Where the split tree keeps its nodes, at addresses that stay put. A worker's own allocations
// stay resident in its malloc arena once freed (glibc keeps a thread arena's free top while its
// trim threshold, raised by the first large free, exceeds it), so after a decimation every
// worker would hold the nodes it made. The parallel subtrees therefore take their nodes from
// one block the calling thread allocates, each from its share, and only past that share from
// a deque of their own.
class ClusterStore {
 public:
  ClusterStore() = default;
  ClusterStore(Cluster* block, std::size_t capacity) : block_(block), capacity_(capacity) {}
  Cluster& add(const Cluster& c) {
    if (used_ < capacity_) return *new (block_ + used_++) Cluster(c);
    return overflow_.emplace_back(c);
  }

 private:
  Cluster* block_ = nullptr;
  std::size_t capacity_ = 0, used_ = 0;
  std::deque<Cluster> overflow_;
};

// Room for n clusters, allocated but not constructed, so that the pages of a share that goes
// unused are never touched. Empty where the address space cannot be had (a ulimit, no
// overcommit): every subtree then keeps a deque.
class ReservedClusters {
 public:
  explicit ReservedClusters(std::size_t n) : n_(n) {
    try { data_ = std::allocator<Cluster>().allocate(n); } catch (const std::bad_alloc&) { data_ = nullptr; }
  }
  ~ReservedClusters() { if (data_) std::allocator<Cluster>().deallocate(data_, n_); }
  ReservedClusters(const ReservedClusters&) = delete;
  ReservedClusters& operator=(const ReservedClusters&) = delete;
  Cluster* data() const { return data_; }

 private:
  Cluster* data_ = nullptr;
  std::size_t n_;
};

// Splits c through its centroid along its axis (or by side, see describe_sides), in place and
// without a branch (which side a point falls on is a coin toss, and mispredicting it cost most
// of the time): each point is swapped with the first point not known to be below, which then
// advances past it if it is below. Then both halves are summed about c's centroid. Returns
// false, and marks c unsplittable, when every point falls on one side.
bool split(Cluster& c, Working& w, ClusterStore& store, double max_variation) {
  const Vec3 o = c.centroid;
  const Vec3 axis = c.axis;
  double* x = w.xyz.data();
  Index* idx = w.index.data();
  const bool sheets = !w.nrm.empty();
  double* nr = w.nrm.data();
  std::size_t lo = c.begin;  // [begin, lo) below, [lo, i) not below
  if (c.by_side) {
    const Vec3 u = c.side_axis;
    for (std::size_t i = c.begin; i < c.end; ++i) {
      const bool below = nr[3 * i] * u.x() + nr[3 * i + 1] * u.y() + nr[3 * i + 2] * u.z() < 0.0;
      if (below) {
        for (int a = 0; a < 3; ++a) { std::swap(x[3 * i + a], x[3 * lo + a]); std::swap(nr[3 * i + a], nr[3 * lo + a]); }
        std::swap(idx[i], idx[lo]);
        ++lo;
      }
    }
    if (lo == c.begin || lo == c.end) {
      // Its normals disagree but none faces away from the axis: split it through space instead.
      c.by_side = false;
      return split(c, w, store, max_variation);
    }
  } else {
    for (std::size_t i = c.begin; i < c.end; ++i) {
      const double px = x[3 * i], py = x[3 * i + 1], pz = x[3 * i + 2];
      const Index pi = idx[i];
      x[3 * i] = x[3 * lo]; x[3 * i + 1] = x[3 * lo + 1]; x[3 * i + 2] = x[3 * lo + 2];
      idx[i] = idx[lo];
      x[3 * lo] = px; x[3 * lo + 1] = py; x[3 * lo + 2] = pz;
      idx[lo] = pi;
      if (sheets) {
        const double nx = nr[3 * i], ny = nr[3 * i + 1], nz = nr[3 * i + 2];
        nr[3 * i] = nr[3 * lo]; nr[3 * i + 1] = nr[3 * lo + 1]; nr[3 * i + 2] = nr[3 * lo + 2];
        nr[3 * lo] = nx; nr[3 * lo + 1] = ny; nr[3 * lo + 2] = nz;
      }
      lo += (px - o.x()) * axis.x() + (py - o.y()) * axis.y() + (pz - o.z()) * axis.z() < 0.0;
    }
  }
  if (lo == c.begin || lo == c.end) { c.splittable = false; return false; }
  Moments below_sums, above_sums;
  for (std::size_t i = c.begin; i < lo; ++i) below_sums.add(&x[3 * i], o);
  for (std::size_t i = lo; i < c.end; ++i) above_sums.add(&x[3 * i], o);
  Cluster* a = &store.add(Cluster{c.begin, lo, Vec3::Zero(), Vec3::Zero(), 0.0, false});
  Cluster* b = &store.add(Cluster{lo, c.end, Vec3::Zero(), Vec3::Zero(), 0.0, false});
  describe(*a, o, static_cast<double>(lo - c.begin), below_sums, max_variation);
  describe(*b, o, static_cast<double>(c.end - lo), above_sums, max_variation);
  if (sheets) {
    describe_sides(*a, w, c.begin, lo);
    describe_sides(*b, w, lo, c.end);
  }
  c.child[0] = a;
  c.child[1] = b;
  return true;
}

// Splits c and its descendants down to clusters of fewer than `smallest` points.
// (A stack, not recursion: a lopsided cloud can make the tree deep.)
void split_down(Cluster& c, Working& w, ClusterStore& store, std::size_t smallest, double max_variation) {
  std::vector<Cluster*> stack{&c};
  while (!stack.empty()) {
    Cluster* t = stack.back();
    stack.pop_back();
    if (!t->splittable || t->end - t->begin < smallest || !split(*t, w, store, max_variation)) continue;
    stack.push_back(t->child[1]);
    stack.push_back(t->child[0]);
  }
}

// The open clusters, largest priority first. Priorities are whole numbers (a size, times 4 for a
// curved cluster), so the small ones, which nearly all pops are, sit in buckets, one per value;
// a binary heap over them would wait on memory. Ties go last in, first out (either order leaves
// the clusters that stay unsplit, where the target is reached part way through a bucket, spread
// evenly).
class BestFirst {
 public:
  void push(Cluster* c) {
    ++size_;
    if (c->priority >= static_cast<double>(buckets_)) { large_.push({c->priority, c}); return; }
    const auto p = static_cast<std::size_t>(c->priority);
    bucket_[p].push_back(c);
    top_ = std::max(top_, p);
  }
  Cluster* pop() {
    --size_;
    if (!large_.empty()) { Cluster* c = large_.top().cluster; large_.pop(); return c; }
    while (bucket_[top_].empty()) --top_;
    std::vector<Cluster*>& b = bucket_[top_];
    Cluster* c = b.back();
    b.pop_back();
    return c;
  }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

 private:
  struct Queued {
    double priority;
    Cluster* cluster;
    bool operator<(const Queued& o) const { return priority < o.priority; }
  };
  static constexpr std::size_t buckets_ = 4096;
  std::vector<std::vector<Cluster*>> bucket_ = std::vector<std::vector<Cluster*>>(buckets_);
  std::priority_queue<Queued> large_;
  std::size_t top_ = 0, size_ = 0;
};

}  // namespace

Clustering cluster_decimate(const Points& points, std::size_t target, double max_variation,
                            const IndexList* read_order, const Points* side_normals) {
  check_decimation(points, static_cast<long long>(std::min<std::size_t>(target, 1ull << 62)), max_variation);
  const std::size_t n = static_cast<std::size_t>(points.rows());
  target = std::max<std::size_t>(1, std::min(target, n));
  if (n == 0) return Clustering{};
  Working w;
  w.index.resize(n);
  if (read_order && read_order->size() == n) {
    w.xyz.resize(3 * n);
    parallel_for(n, [&](std::size_t b, std::size_t e) {
      for (std::size_t j = b; j < e; ++j) {
        const Index i = (*read_order)[j];
        w.index[j] = i;
        for (int a = 0; a < 3; ++a) w.xyz[3 * j + a] = points(i, a);
      }
    });
  } else {
    w.xyz.assign(points.data(), points.data() + 3 * n);
    for (std::size_t i = 0; i < n; ++i) w.index[i] = static_cast<Index>(i);
  }
  if (side_normals && side_normals->rows() == points.rows()) {
    w.nrm.resize(3 * n);
    for (std::size_t j = 0; j < n; ++j)
      for (int a = 0; a < 3; ++a) w.nrm[3 * j + a] = (*side_normals)(w.index[j], a);
  }

  // The split of a cluster depends on its points alone, so the large ones, which nearly all
  // get split, are split ahead of time in parallel subtrees; the best-first order below then
  // replays the same sequence as a serial run, splitting the rest when it reaches them.
  const std::size_t smallest = std::max<std::size_t>(2, n / target);
  w.side_split_limit = side_split_sizes * smallest;
  std::deque<Cluster> top;
  Cluster& root = top.emplace_back(whole(w, max_variation));
  std::vector<Cluster*> frontier{&root};
  const std::size_t wanted = 16 * static_cast<std::size_t>(thread_count());
  // Level by level while there are fewer subtrees than workers want, each level in parallel.
  std::deque<ClusterStore> level_stores;  // one per split, kept for the nodes' addresses
  while (!frontier.empty() && frontier.size() < wanted) {
    std::vector<unsigned char> was_split(frontier.size(), 0);
    std::vector<ClusterStore*> store(frontier.size());
    for (auto& s : store) s = &level_stores.emplace_back();
    parallel_for(frontier.size(), [&](std::size_t b, std::size_t e) {
      for (std::size_t t = b; t < e; ++t) {
        Cluster& c = *frontier[t];
        was_split[t] = c.splittable && c.end - c.begin >= smallest && split(c, w, *store[t], max_variation);
      }
    }, {}, 1);
    std::vector<Cluster*> next;
    for (std::size_t t = 0; t < frontier.size(); ++t)
      if (was_split[t]) { next.push_back(frontier[t]->child[0]); next.push_back(frontier[t]->child[1]); }
    frontier.swap(next);
  }
  // A subtree of s points ends in clusters of about smallest / 2 points or more, so it makes
  // about 4 s / smallest nodes; its share is 6 s / smallest + 16, and more spill over into
  // its own deque.
  std::vector<std::size_t> share(frontier.size() + 1, 0);
  for (std::size_t t = 0; t < frontier.size(); ++t)
    share[t + 1] = share[t] + 6 * (frontier[t]->end - frontier[t]->begin) / smallest + 16;
  const ReservedClusters block(share.back());
  std::vector<ClusterStore> stores;
  stores.reserve(frontier.size());
  for (std::size_t t = 0; t < frontier.size(); ++t)
    stores.emplace_back(block.data() ? block.data() + share[t] : nullptr, block.data() ? share[t + 1] - share[t] : 0);
  parallel_for(frontier.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) split_down(*frontier[t], w, stores[t], smallest, max_variation);
  }, {}, 1);

  ClusterStore late;
  BestFirst open;
  std::vector<Cluster*> done;
  done.reserve(target);
  open.push(&root);
  while (!open.empty() && open.size() + done.size() < target) {
    Cluster* c = open.pop();
    if (!c->child[0] && !(c->splittable && split(*c, w, late, max_variation))) { done.push_back(c); continue; }
    open.push(c->child[0]);
    open.push(c->child[1]);
  }
  while (!open.empty()) done.push_back(open.pop());

  // Deterministic order: by position in the working arrays (the clusters tile them).
  std::vector<Cluster*> starting_at(n, nullptr);
  for (Cluster* c : done) starting_at[c->begin] = c;
  done.clear();
  for (Cluster* c : starting_at) if (c) done.push_back(c);
  Clustering out;
  out.centroids.resize(static_cast<Eigen::Index>(done.size()), 3);
  out.labels.assign(n, 0);
  for (std::size_t c = 0; c < done.size(); ++c) {
    out.centroids.row(static_cast<Eigen::Index>(c)) = done[c]->centroid.transpose();
    for (std::size_t i = done[c]->begin; i < done[c]->end; ++i) out.labels[w.index[i]] = static_cast<Index>(c);
  }
  return out;
}

}  // namespace pointscale
