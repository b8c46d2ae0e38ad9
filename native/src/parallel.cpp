#include "pointscale/parallel.h"
#include "pointscale/validation.h"
#include "pointscale/worker_pool.h"

#include <algorithm>
#include <atomic>
#include <cfenv>
#include <chrono>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace pointscale {

namespace {
// The count asked for by the innermost ThreadCountScope on this thread; 0 when none was.
thread_local int scoped_threads = 0;

// A worker computes in the calling thread's floating-point environment (its rounding mode, and
// on x86 flush-to-zero), so that no chunk's result depends on the thread it ran on: a kept
// worker was started by an earlier call, and a new thread on Windows starts in the default one.
class CallersFloatingPoint {
 public:
  explicit CallersFloatingPoint(const std::fenv_t& caller) {
    std::fegetenv(&own_);
    std::fesetenv(&caller);
  }
  ~CallersFloatingPoint() { std::fesetenv(&own_); }
  CallersFloatingPoint(const CallersFloatingPoint&) = delete;
  CallersFloatingPoint& operator=(const CallersFloatingPoint&) = delete;

 private:
  std::fenv_t own_;
};

// parallel_for's loop on n_threads - 1 threads started for it, and the calling thread: for a
// loop the kept workers cannot take (worker_pool.h).
template <class HelperShare, class OwnShare>
void with_threads_of_its_own(int n_threads, int call_threads, const HelperShare& helper_share,
                             std::atomic<bool>& stop, const OwnShare& own_share) {
  std::vector<std::thread> workers;
  workers.reserve(n_threads - 1);
  // A thread that fails to start (std::system_error when the process is out of threads or
  // address space) must not unwind past the joinable ones: that calls std::terminate. Stop the
  // started workers, join them, and report the failure to the caller instead.
  try {
    for (int t = 1; t < n_threads; ++t)
      workers.emplace_back([&] {
        ThreadCountScope same_count(call_threads);  // for any loop nested in body, as a kept worker has
        helper_share();
      });
  } catch (const std::exception& e) {
    stop = true;
    for (auto& w : workers) w.join();
    throw std::runtime_error("could not start worker thread " + std::to_string(workers.size() + 1) + " of " +
                             std::to_string(n_threads - 1) + " (" + e.what() +
                             "); the work was stopped: ask for fewer threads");
  }
  own_share();
  for (auto& w : workers) w.join();
}
}  // namespace

ThreadCountScope::ThreadCountScope(int threads) : previous_(scoped_threads) {
  check_threads(threads);
  scoped_threads = threads;
}

ThreadCountScope::~ThreadCountScope() { scoped_threads = previous_; }

int thread_count() {
  if (scoped_threads > 0) return scoped_threads;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

void parallel_for(std::size_t n, const std::function<void(std::size_t, std::size_t)>& body,
                  const ProgressStage& stage, std::size_t chunk) {
  if (n == 0) return;
  chunk = std::max<std::size_t>(1, chunk);
  const std::size_t n_chunks = (n + chunk - 1) / chunk;
  const int call_threads = thread_count();
  const int n_threads = static_cast<int>(std::min<std::size_t>(call_threads, n_chunks));

  std::atomic<std::size_t> next{0};
  std::atomic<std::size_t> done{0};
  std::atomic<bool> stop{false};
  std::exception_ptr error;
  std::mutex error_mutex;

  auto work_one = [&]() -> bool {
    if (stop.load(std::memory_order_relaxed)) return false;
    std::size_t c = next.fetch_add(1);
    if (c >= n_chunks) return false;
    std::size_t b = c * chunk, e = std::min(n, b + chunk);
    try {
      body(b, e);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      stop = true;
      return false;
    }
    done.fetch_add(e - b);
    return true;
  };

  // The calling thread works and is the only one that talks to the progress callback.
  auto own_share = [&] {
    auto last = std::chrono::steady_clock::now();
    while (work_one()) {
      auto now = std::chrono::steady_clock::now();
      if (stage.callback && now - last > std::chrono::milliseconds(50)) {
        last = now;
        try {
          stage.report(static_cast<double>(done.load()) / static_cast<double>(n));
        } catch (...) {
          std::lock_guard<std::mutex> lock(error_mutex);
          if (!error) error = std::current_exception();
          stop = true;
        }
      }
    }
  };
  std::fenv_t env;
  std::fegetenv(&env);
  const auto helper_share = [&] {
    CallersFloatingPoint same_arithmetic(env);
    while (work_one()) {}
  };
  if (n_threads == 1 || !run_on_kept_workers(n_threads - 1, call_threads, helper_share, own_share))
    with_threads_of_its_own(n_threads, call_threads, helper_share, stop, own_share);
  if (error) std::rethrow_exception(error);
  stage.report(1.0);
}

}  // namespace pointscale
