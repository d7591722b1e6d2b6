// The fixed thread pool of the filter's particles (thread_pool.h).
#include "omnislam/runtime/thread_pool.h"

#include <map>
#include <memory>
#include <stdexcept>

namespace omnislam::runtime {

ThreadPool::ThreadPool(std::size_t threads) {
  if (threads == 0) throw std::invalid_argument("ThreadPool: threads must be >= 1");
  threads_.reserve(threads - 1);
  for (std::size_t w = 1; w < threads; ++w) threads_.emplace_back([this, w] { threadLoop(w); });
}

ThreadPool::~ThreadPool() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  start_.notify_all();
  for (auto& t : threads_) t.join();
}

void ThreadPool::run(std::size_t n, const Body& body) {
  if (n == 0) return;
  const std::lock_guard<std::mutex> one_run(run_mutex_);
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    body_ = &body;
    n_ = n;
    next_ = finished_ = 0;
    error_ = nullptr;
    ++generation_;
  }
  start_.notify_all();
  work(0);
  // Every call is taken (work returned): wait for those still running elsewhere. A thread that
  // wakes later finds nothing to take, and never touches body_ again.
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return finished_ == n_; });
  body_ = nullptr;
  if (error_) {
    std::exception_ptr e = error_;
    error_ = nullptr;
    std::rethrow_exception(e);
  }
}

void ThreadPool::threadLoop(std::size_t worker) {
  std::uint64_t seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
    }
    work(worker);
  }
}

void ThreadPool::work(std::size_t worker) {
  std::unique_lock<std::mutex> lock(mutex_);
  while (next_ < n_) {
    const std::size_t i = next_++;
    const Body& body = *body_;
    lock.unlock();
    std::exception_ptr error;
    try {
      body(i, worker);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    if (error && (!error_ || i < error_index_)) {
      error_ = error;
      error_index_ = i;
    }
    if (++finished_ == n_) done_.notify_one();
  }
}

ParallelFor* sharedThreadPool(int threads) {
  if (threads <= 1) return nullptr;
  static std::mutex mutex;
  static std::map<int, std::unique_ptr<ThreadPool>> pools;
  const std::lock_guard<std::mutex> lock(mutex);
  auto& pool = pools[threads];
  if (!pool) pool = std::make_unique<ThreadPool>(static_cast<std::size_t>(threads));
  return pool.get();
}

}  // namespace omnislam::runtime
