#include "pointscale/worker_pool.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "pointscale/parallel.h"

#if defined(__unix__) || defined(__APPLE__)
#include <pthread.h>
#define POINTSCALE_HAS_ATFORK 1
#endif

namespace pointscale {

namespace {

// How long a worker watches for the next loop before it sleeps: the loops of one call follow
// each other within microseconds, and a sleeping worker takes about as long to wake as a new
// thread takes to start. Between calls the workers sleep, and use no CPU.
constexpr std::chrono::microseconds watch_for_next(200);

class WorkerPool {
 public:
  bool run(int helpers, int call_threads, const std::function<void()>& work, const std::function<void()>& own_share) {
    if (helpers < 1 || helpers > max_helpers()) return false;
    bool expected = false;
    if (!busy_.compare_exchange_strong(expected, true, std::memory_order_acquire)) return false;
    if (!grow_to(helpers)) {
      busy_.store(false, std::memory_order_release);
      return false;
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      job_ = &work;
      job_threads_ = call_threads;
      wanted_ = helpers;
      generation_.fetch_add(1, std::memory_order_release);
    }
    wake_.notify_all();
    std::exception_ptr error;
    try {
      own_share();
    } catch (...) {
      error = std::current_exception();
    }
    {
      // Withdraw the calls no worker has started, and wait for those that did.
      std::unique_lock<std::mutex> lock(mutex_);
      wanted_ = 0;
      finished_.wait(lock, [&] { return running_ == 0; });
      job_ = nullptr;
    }
    busy_.store(false, std::memory_order_release);
    if (error) std::rethrow_exception(error);
    return true;
  }

 private:
  // The calling thread is the first of a call's threads, so the workers fill the other cores.
  static int max_helpers() {
    return std::max(0, static_cast<int>(std::thread::hardware_concurrency()) - 1);
  }

  bool grow_to(int helpers) {
    try {
      // A new worker counts the loops from the one about to be handed out, so it takes that one
      // at once instead of watching for the next.
      const unsigned before = generation_.load(std::memory_order_acquire);
      while (static_cast<int>(count_) < helpers) {
        std::thread(&WorkerPool::serve, this, before).detach();
        ++count_;
      }
    } catch (...) {  // std::system_error: out of threads or address space
      return false;
    }
    return true;
  }

  void serve(unsigned seen) {
    for (;;) {
      const auto start = std::chrono::steady_clock::now();
      while (generation_.load(std::memory_order_acquire) == seen &&
             std::chrono::steady_clock::now() - start < watch_for_next)
        std::this_thread::yield();
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return wanted_ > 0; });
      seen = generation_.load(std::memory_order_acquire);
      --wanted_;
      ++running_;
      const std::function<void()>* job = job_;
      const int threads = job_threads_;
      lock.unlock();
      try {
        ThreadCountScope same_count(threads);  // for any loop nested in the work
        (*job)();
      } catch (...) {
        // work() catches what its body throws; a count that could not be set has already
        // been checked by the call that asked for it.
      }
      lock.lock();
      if (--running_ == 0) finished_.notify_all();
    }
  }

  std::atomic<bool> busy_{false};  // a loop holds the workers
  std::size_t count_ = 0;          // workers started (changed only by the loop holding busy_)
  std::mutex mutex_;
  std::condition_variable wake_, finished_;
  std::atomic<unsigned> generation_{0};  // counts the loops handed out, for the watching workers
  const std::function<void()>* job_ = nullptr;
  int job_threads_ = 1;
  int wanted_ = 0;   // calls of job_ not yet started by a worker
  int running_ = 0;  // calls of job_ running on workers
};

// The pool lives as long as the process and is never destroyed: its detached workers wait on
// its condition variables, and destroying those under them at exit would hang or crash. A
// child made by fork() has none of its parent's workers, so it starts a pool of its own.
std::atomic<WorkerPool*> the_pool{nullptr};

#if POINTSCALE_HAS_ATFORK
void new_pool_in_child() { the_pool.store(nullptr); }
#endif

WorkerPool& pool() {
  static const bool once = [] {
#if POINTSCALE_HAS_ATFORK
    pthread_atfork(nullptr, nullptr, new_pool_in_child);
#endif
    return true;
  }();
  (void)once;
  WorkerPool* p = the_pool.load(std::memory_order_acquire);
  if (!p) {
    WorkerPool* made = new WorkerPool;
    if (the_pool.compare_exchange_strong(p, made, std::memory_order_acq_rel)) return *made;
    delete made;  // another thread made one first; p is that one
  }
  return *p;
}

}  // namespace

bool run_on_kept_workers(int helpers, int call_threads, const std::function<void()>& work,
                         const std::function<void()>& own_share) {
  return pool().run(helpers, call_threads, work, own_share);
}

}  // namespace pointscale
