// A small fixed pool of threads implementing the core's ParallelFor (omnislam/core/parallel_for.h):
// the filter's particles of a step run on it (filter.threads). The threads sleep on a condition
// variable between runs (no busy waiting); the calling thread works too, and waits only for the
// calls other threads have taken, so a pool thread that a loaded machine does not schedule in time
// costs nothing (the caller does its share).
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "omnislam/core/parallel_for.h"

namespace omnislam::runtime {

class ThreadPool final : public ParallelFor {
 public:
  /// `threads` >= 1 workers: the thread calling run() and threads - 1 threads started here (and
  /// joined by the destructor). Throws std::invalid_argument for 0.
  explicit ThreadPool(std::size_t threads);
  ~ThreadPool() override;
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  std::size_t workers() const override { return threads_.size() + 1; }
  /// ParallelFor::run: the indices are taken one at a time by whichever worker is free. One run at
  /// a time (a second caller waits for the first).
  void run(std::size_t n, const Body& body) override;

 private:
  void threadLoop(std::size_t worker);
  void work(std::size_t worker);  // takes indices of the current run until none is left

  std::vector<std::thread> threads_;
  std::mutex run_mutex_;  // one run at a time
  std::mutex mutex_;      // the fields below
  std::condition_variable start_, done_;
  std::uint64_t generation_ = 0;  // runs started
  bool stopping_ = false;
  const Body* body_ = nullptr;
  std::size_t n_ = 0, next_ = 0;  // calls of the current run, the next one to take
  std::size_t finished_ = 0;      // calls of the current run that have returned
  std::exception_ptr error_;
  std::size_t error_index_ = 0;
};

/// The process's pool of `threads` workers, started at the first call with that count and kept
/// until exit; nullptr for threads <= 1 (FastSlam::step then runs the particles on its caller).
ParallelFor* sharedThreadPool(int threads);

}  // namespace omnislam::runtime
