// Progress reporting with cancellation. The callback is only ever called from the thread
// that started the work (the one that may hold a Python GIL), never from a worker.
#pragma once
#include <functional>
#include <stdexcept>
#include <string>

namespace pointscale {

// Thrown when the progress callback asked to stop; no result is produced.
struct Cancelled : std::runtime_error {
  Cancelled() : std::runtime_error("cancelled by the progress callback") {}
};

// Receives the overall fraction in [0,1]; returns false to cancel.
using ProgressCallback = std::function<bool(double)>;

// A slice [begin, end] of the overall progress, handed to one stage of the work.
struct ProgressStage {
  const ProgressCallback* callback = nullptr;
  double begin = 0.0;
  double end = 1.0;

  // Reports a local fraction of this stage; throws Cancelled if the callback says stop.
  void report(double local_fraction) const {
    if (callback && *callback && !(*callback)(begin + (end - begin) * local_fraction)) throw Cancelled();
  }
  // The sub-stage covering [a, b] of this stage.
  ProgressStage sub(double a, double b) const {
    return {callback, begin + (end - begin) * a, begin + (end - begin) * b};
  }
};

}  // namespace pointscale
