// The executor the filter runs its particles on (FastSlam::step): an interface, so that the core
// stays free of threads. SequentialFor (the default) runs the calls in index order on the caller's
// thread; the thread pool that implements it on several cores is in common/runtime (thread_pool.h).
#pragma once

#include <cstddef>
#include <functional>

namespace omnislam {

class ParallelFor {
 public:
  /// One call: the index in [0, n) and the worker running it, in [0, workers()); two calls that run
  /// at the same time never have the same worker (per-worker scratch needs no lock).
  using Body = std::function<void(std::size_t index, std::size_t worker)>;
  virtual ~ParallelFor() = default;
  /// How many calls may run at once (>= 1).
  virtual std::size_t workers() const = 0;
  /// Calls body(i, worker) once for every i in [0, n), in any order and at once on up to workers()
  /// threads, and returns when every call has returned. When calls throw, the exception of the
  /// lowest index that threw is rethrown (SequentialFor stops there; a pool lets the others finish).
  /// The callers' results must not depend on the order: each call writes only its own index's data.
  virtual void run(std::size_t n, const Body& body) = 0;
};

/// Every call in index order on the caller's thread, worker 0.
class SequentialFor final : public ParallelFor {
 public:
  std::size_t workers() const override { return 1; }
  void run(std::size_t n, const Body& body) override {
    for (std::size_t i = 0; i < n; ++i) body(i, 0);
  }
};

}  // namespace omnislam
