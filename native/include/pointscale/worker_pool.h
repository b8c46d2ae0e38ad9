// Worker threads kept between parallel loops: parallel_for's helpers when it can have them.
// Starting and joining a thread costs as much as a short loop's work, and a fold limiter round
// or a reconstruction runs dozens of short loops in a row.
#pragma once
#include <functional>

namespace pointscale {

// Runs work() on up to `helpers` kept workers and own_share() on the calling thread at once,
// and returns when every call has returned; workers that had not started work() by the time
// own_share() returned never start it. Each worker's call runs inside
// ThreadCountScope(call_threads). work() must not throw; what own_share() throws is rethrown
// once the workers are done.
//
// Returns false, having run nothing, when the kept workers cannot take the loop: another loop
// holds them (a loop nested in a worker's work, or a second thread calling the core), more
// helpers are asked for than the machine has cores beyond the calling thread's, or a worker
// could not be started. The caller then starts threads of its own.
bool run_on_kept_workers(int helpers, int call_threads, const std::function<void()>& work,
                         const std::function<void()>& own_share);

}  // namespace pointscale
