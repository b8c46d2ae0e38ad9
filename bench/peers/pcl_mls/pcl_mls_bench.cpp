// One PCL MLS pass (polynomial order 1), timed: the peer for bench/run.py.
//
//   pcl_mls_bench INPUT K [--threads T] [--radius R] [--calib-samples S] [--reps N] [--out FILE]
//
// INPUT is either a headerless little-endian float32 file of n*3 values (x y z ...),
// or a PLY file (extension .ply, read with pcl::io::loadPLYFile; only x y z used).
// K is the neighbour count pointscale uses (kNN). PCL's MLS takes a search radius,
// so unless --radius is given the radius is calibrated (outside the timed region)
// so that the mean number of neighbours inside it over a random sample of points
// equals K; the mean count actually obtained is printed.
//
// Prints ONE JSON line on stdout. "process_s" is the wall time of
// MovingLeastSquares::process() only (it includes PCL's own kd-tree build, as
// pointscale's decompose includes its own). With --reps N the pass is repeated on a
// fresh MovingLeastSquares object N times and "process_s" is the median
// ("process_all_s" lists every run); peak RSS is read after the first run.
#include <pcl/point_types.h>
#include <pcl/point_cloud.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/mls.h>
#include <pcl/io/ply_io.h>

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <random>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

double cpu_seconds() {  // user + system time of the whole process, all threads
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_utime.tv_sec + ru.ru_stime.tv_sec + 1e-6 * (ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

// VmRSS / VmHWM of this process image in KiB (-1 if unavailable). Not ru_maxrss: on
// Linux a child inherits its parent's peak RSS through fork/exec, so a Python parent
// that once held a big cloud would inflate it.
long status_kib(const char* key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  const std::size_t len = std::strlen(key);
  while (std::getline(f, line))
    if (line.compare(0, len, key) == 0) return std::atol(line.c_str() + len + 1);
  return -1;
}

bool reset_peak_rss() {  // VmHWM := VmRSS (Linux >= 4.0)
  std::ofstream f("/proc/self/clear_refs");
  if (!f) return false;
  f << "5";
  f.flush();
  return static_cast<bool>(f);
}

long maxrss_kib() {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss;  // KiB on Linux
}

bool ends_with(const std::string& s, const std::string& suf) {
  return s.size() >= suf.size() &&
         std::equal(suf.rbegin(), suf.rend(), s.rbegin(),
                    [](char a, char b) { return std::tolower(a) == std::tolower(b); });
}

[[noreturn]] void die(const std::string& msg) {
  std::cerr << "pcl_mls_bench: " << msg << "\n";
  std::exit(2);
}

pcl::PointCloud<pcl::PointXYZ>::Ptr load(const std::string& path) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  if (ends_with(path, ".ply")) {
    if (pcl::io::loadPLYFile<pcl::PointXYZ>(path, *cloud) < 0) die("cannot read PLY " + path);
    return cloud;
  }
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  if (!f) die("cannot open " + path);
  const std::streamsize bytes = f.tellg();
  if (bytes <= 0 || bytes % (3 * sizeof(float)) != 0)
    die(path + ": size is not a multiple of 12 bytes (float32 x y z)");
  const std::size_t n = static_cast<std::size_t>(bytes) / (3 * sizeof(float));
  std::vector<float> buf(3 * n);
  f.seekg(0);
  f.read(reinterpret_cast<char*>(buf.data()), bytes);
  if (!f) die("short read on " + path);
  cloud->resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    (*cloud)[i].x = buf[3 * i];
    (*cloud)[i].y = buf[3 * i + 1];
    (*cloud)[i].z = buf[3 * i + 2];
  }
  cloud->width = static_cast<std::uint32_t>(n);
  cloud->height = 1;
  cloud->is_dense = true;
  return cloud;
}

// Mean neighbour count (the query point included, as in PCL's MLS neighbourhood)
// within radius r over the sample.
double mean_count(const pcl::KdTreeFLANN<pcl::PointXYZ>& tree,
                  const pcl::PointCloud<pcl::PointXYZ>& cloud,
                  const std::vector<int>& sample, double r) {
  std::vector<int> idx;
  std::vector<float> d2;
  double total = 0;
  for (int i : sample) {
    total += tree.radiusSearch(cloud[i], r, idx, d2);
  }
  return total / static_cast<double>(sample.size());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: pcl_mls_bench INPUT K [--threads T] [--radius R] "
                 "[--calib-samples S] [--reps N] [--out FILE]\n";
    return 2;
  }
  const std::string path = argv[1];
  const int k = std::atoi(argv[2]);
  if (k < 3) die("K must be >= 3");
  int threads = 2;
  double radius = 0;
  int calib_samples = 20000;
  int reps = 1;
  std::string out_path;
  for (int a = 3; a < argc; ++a) {
    std::string s = argv[a];
    auto next = [&]() -> const char* {
      if (a + 1 >= argc) die("missing value after " + s);
      return argv[++a];
    };
    if (s == "--threads") threads = std::atoi(next());
    else if (s == "--radius") radius = std::atof(next());
    else if (s == "--calib-samples") calib_samples = std::atoi(next());
    else if (s == "--out") out_path = next();
    else if (s == "--reps") reps = std::max(1, std::atoi(next()));
    else die("unknown option " + s);
  }

  auto t0 = Clock::now();
  auto cloud = load(path);
  const double load_s = seconds_since(t0);
  const std::size_t n = cloud->size();
  if (n < static_cast<std::size_t>(k)) die("fewer points than K");

  // ---- radius calibration (not timed as part of the MLS pass) ----
  t0 = Clock::now();
  std::mt19937_64 rng(12345);
  std::vector<int> sample;
  {
    const std::size_t s = std::min<std::size_t>(n, static_cast<std::size_t>(calib_samples));
    if (s == n) {
      sample.resize(n);
      for (std::size_t i = 0; i < n; ++i) sample[i] = static_cast<int>(i);
    } else {
      std::uniform_int_distribution<std::size_t> pick(0, n - 1);
      sample.resize(s);
      for (auto& i : sample) i = static_cast<int>(pick(rng));
    }
  }
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(cloud);
  double achieved = 0;
  int calib_iters = 0;
  const bool calibrated = radius <= 0;
  if (calibrated) {
    // Start from the mean distance to the K-th nearest neighbour, then bisect on
    // the mean count (monotone in r) until it brackets K to within 0.5%.
    std::vector<int> idx;
    std::vector<float> d2;
    double sum = 0;
    for (int i : sample) {
      tree.nearestKSearch((*cloud)[i], k, idx, d2);
      sum += std::sqrt(static_cast<double>(d2.back()));
    }
    double r = sum / sample.size();
    double lo = 0, hi = 0;
    double c = mean_count(tree, *cloud, sample, r);
    ++calib_iters;
    // Grow/shrink geometrically (count ~ r^2 on a surface) to bracket K.
    while (c < k) { lo = r; r *= std::sqrt(static_cast<double>(k) / std::max(c, 1.0)) * 1.05;
                    c = mean_count(tree, *cloud, sample, r); ++calib_iters; }
    hi = r;
    double chi = c;
    if (lo == 0) {
      lo = r;
      double clo = c;
      while (clo >= k) { hi = lo; chi = clo; lo *= std::sqrt(k / clo) * 0.95;
                         clo = mean_count(tree, *cloud, sample, lo); ++calib_iters; }
    }
    radius = hi;
    achieved = chi;
    for (int it = 0; it < 40 && std::abs(achieved - k) > 0.005 * k; ++it) {
      const double mid = 0.5 * (lo + hi);
      const double cm = mean_count(tree, *cloud, sample, mid);
      ++calib_iters;
      if (cm < k) lo = mid; else { hi = mid; radius = mid; achieved = cm; }
    }
  } else {
    achieved = mean_count(tree, *cloud, sample, radius);
  }
  // Median count too (raw scans have very uneven density).
  std::vector<int> counts;
  counts.reserve(sample.size());
  {
    std::vector<int> idx;
    std::vector<float> d2;
    for (int i : sample) counts.push_back(tree.radiusSearch((*cloud)[i], radius, idx, d2));
  }
  std::nth_element(counts.begin(), counts.begin() + counts.size() / 2, counts.end());
  const int median_count = counts[counts.size() / 2];
  const double calib_s = seconds_since(t0);

  // ---- the timed MLS pass(es) ----
  pcl::PointCloud<pcl::PointNormal> out;
  pcl::PointIndicesPtr corr;
  std::vector<double> times, cpu_times;
  long rss_before_kib = 0, rss_after_kib = 0;
  bool peak_reset = false;
  for (int r = 0; r < reps; ++r) {
    pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointNormal> mls;
    pcl::search::KdTree<pcl::PointXYZ>::Ptr search(new pcl::search::KdTree<pcl::PointXYZ>);
    mls.setInputCloud(cloud);
    mls.setSearchMethod(search);
    mls.setSearchRadius(radius);
    mls.setPolynomialOrder(1);
    mls.setComputeNormals(true);
    mls.setNumberOfThreads(threads);
    mls.setUpsamplingMethod(pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointNormal>::NONE);
    out.clear();
    if (r == 0) {
      peak_reset = reset_peak_rss();
      rss_before_kib = peak_reset ? status_kib("VmRSS") : status_kib("VmHWM");
    }
    t0 = Clock::now();
    const double c0 = cpu_seconds();
    mls.process(out);
    times.push_back(seconds_since(t0));
    cpu_times.push_back(cpu_seconds() - c0);
    if (r == 0) rss_after_kib = status_kib("VmHWM");
    corr = mls.getCorrespondingIndices();
  }
  std::vector<double> sorted_times = times;
  std::sort(sorted_times.begin(), sorted_times.end());
  const double process_s = sorted_times.size() % 2
      ? sorted_times[sorted_times.size() / 2]
      : 0.5 * (sorted_times[sorted_times.size() / 2 - 1] + sorted_times[sorted_times.size() / 2]);
  std::vector<double> sorted_cpu = cpu_times;
  std::sort(sorted_cpu.begin(), sorted_cpu.end());
  const double process_cpu_s = sorted_cpu.size() % 2
      ? sorted_cpu[sorted_cpu.size() / 2]
      : 0.5 * (sorted_cpu[sorted_cpu.size() / 2 - 1] + sorted_cpu[sorted_cpu.size() / 2]);
  std::string all_times = "[";
  for (std::size_t i = 0; i < times.size(); ++i) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%s%.4f", i ? ", " : "", times[i]);
    all_times += buf;
  }
  all_times += "]";

  // Sanity: mean displacement of the projected points (bbox-diagonal relative).
  double minv[3] = {1e300, 1e300, 1e300}, maxv[3] = {-1e300, -1e300, -1e300};
  for (const auto& p : *cloud) {
    const float v[3] = {p.x, p.y, p.z};
    for (int d = 0; d < 3; ++d) { minv[d] = std::min(minv[d], double(v[d])); maxv[d] = std::max(maxv[d], double(v[d])); }
  }
  const double diag = std::sqrt((maxv[0] - minv[0]) * (maxv[0] - minv[0]) +
                                (maxv[1] - minv[1]) * (maxv[1] - minv[1]) +
                                (maxv[2] - minv[2]) * (maxv[2] - minv[2]));
  // Output order follows PCL's per-thread chunks, so pair points via the indices.
  double disp = 0;
  std::size_t finite = 0;
  if (corr && corr->indices.size() == out.size()) {
    for (std::size_t j = 0; j < out.size(); ++j) {
      const auto& q = out[j];
      const auto& p = (*cloud)[corr->indices[j]];
      if (!std::isfinite(q.x)) continue;
      const double dx = q.x - p.x, dy = q.y - p.y, dz = q.z - p.z;
      disp += std::sqrt(dx * dx + dy * dy + dz * dz);
      ++finite;
    }
  }

  if (!out_path.empty()) {
    std::ofstream f(out_path, std::ios::binary);
    for (const auto& q : out) {
      const float v[6] = {q.x, q.y, q.z, q.normal_x, q.normal_y, q.normal_z};
      f.write(reinterpret_cast<const char*>(v), sizeof v);
    }
  }

  std::printf(
      "{\"peer\": \"pcl::MovingLeastSquares\", \"pcl_version\": \"%s\", \"n\": %zu, "
      "\"k_target\": %d, \"radius\": %.9g, \"radius_calibrated\": %s, "
      "\"mean_neighbors\": %.3f, \"median_neighbors\": %d, \"calib_samples\": %zu, "
      "\"calib_iters\": %d, \"polynomial_order\": 1, \"threads\": %d, "
      "\"load_s\": %.4f, \"calib_s\": %.4f, \"process_s\": %.4f, \"process_all_s\": %s, \"process_cpu_s\": %.4f, \"n_out\": %zu, "
      "\"mean_disp_rel\": %.3g, \"peak_reset\": %s, \"rss_before_kib\": %ld, \"hwm_after_kib\": %ld, "
      "\"ru_maxrss_kib\": %ld}\n",
      PCL_VERSION_PRETTY, n, k, radius, calibrated ? "true" : "false", achieved, median_count,
      sample.size(), calib_iters, threads, load_s, calib_s, process_s, all_times.c_str(), process_cpu_s, out.size(),
      finite ? disp / finite / diag : -1.0, peak_reset ? "true" : "false", rss_before_kib,
      rss_after_kib, maxrss_kib());
  return 0;
}
