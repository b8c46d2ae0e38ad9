// A chunked parallel loop on std::thread that reports progress from the calling thread and
// stops every worker early when the progress callback cancels.
#pragma once
#include <cstddef>
#include <functional>

#include "pointscale/progress.h"

namespace pointscale {

// Sets how many threads the core's calls made on this thread use, until it goes out of scope
// (0: all hardware threads, the default). A caller such as the Python bindings makes one per
// call around the work. The count belongs to the calling thread, not to the process, so two
// threads calling the core at once with different counts do not see each other's, and a count
// asked for one call does not stay behind for the next. parallel_for's workers take the
// count of the call that started them, so work nested inside a loop keeps to it too.
class ThreadCountScope {
 public:
  explicit ThreadCountScope(int threads);  // std::invalid_argument outside 0..max_threads (check_threads, validation.h)
  ~ThreadCountScope();
  ThreadCountScope(const ThreadCountScope&) = delete;
  ThreadCountScope& operator=(const ThreadCountScope&) = delete;

 private:
  int previous_;
};

// The number of threads the current call uses (ThreadCountScope), at least 1.
int thread_count();

// Calls body(begin, end) on disjoint chunks covering [0, n). The calling thread works too and
// reports progress to `stage` about every 50 ms. The other threads are kept workers
// (worker_pool.h) when they are free, else threads started for this loop. Exceptions (including Cancelled) are rethrown
// in the calling thread after all workers stopped. A worker thread that the system cannot start
// stops and joins the ones that did start, then throws std::runtime_error (RuntimeError in Python).
void parallel_for(std::size_t n, const std::function<void(std::size_t, std::size_t)>& body,
                  const ProgressStage& stage = {}, std::size_t chunk = 256);

}  // namespace pointscale
