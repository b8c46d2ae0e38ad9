// A chunked parallel loop on std::thread that reports progress from the calling thread and
// stops every worker early when the progress callback cancels.
#pragma once
#include <cstddef>
#include <functional>

#include "pointscale/progress.h"

namespace pointscale {

// Number of threads used by the core: set_thread_count(0) means all hardware threads.
void set_thread_count(int threads);
int thread_count();

// Calls body(begin, end) on disjoint chunks covering [0, n). The calling thread works too and
// reports progress to `stage` about every 50 ms. Exceptions (including Cancelled) are rethrown
// in the calling thread after all workers stopped. A worker thread that the system cannot start
// stops and joins the ones that did start, then throws std::runtime_error (RuntimeError in Python).
void parallel_for(std::size_t n, const std::function<void(std::size_t, std::size_t)>& body,
                  const ProgressStage& stage = {}, std::size_t chunk = 256);

}  // namespace pointscale
