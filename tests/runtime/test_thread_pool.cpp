// The thread pool of the filter's particles (common/runtime/thread_pool.h): every index once, on
// workers below workers(), exceptions of the lowest index rethrown after the rest ran, many runs on
// one pool; and the filter on it with 1, 2 and 4 threads: the same saved state, byte for byte.
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "../core/slam_scenarios.h"
#include "omnislam/core/slam/fastslam.h"
#include "omnislam/runtime/thread_pool.h"

using namespace omnislam;
using namespace omnislam::slam;
using omnislam::runtime::ThreadPool;

TEST(runtime_ThreadPool, RunsEveryIndexOnceOnItsWorkers) {
  for (const std::size_t threads : {1u, 2u, 4u}) {
    ThreadPool pool(threads);
    EXPECT_EQ(pool.workers(), threads);
    for (const std::size_t n : {0u, 1u, 3u, 1000u}) {
      std::vector<std::atomic<int>> count(n);
      std::atomic<bool> bad_worker{false};
      pool.run(n, [&](std::size_t i, std::size_t worker) {
        ++count[i];
        if (worker >= threads) bad_worker = true;
      });
      for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(count[i].load(), 1) << threads << " threads, index " << i;
      EXPECT_FALSE(bad_worker.load());
    }
  }
}

TEST(runtime_ThreadPool, TwoCallsAtOnceNeverShareAWorker) {
  ThreadPool pool(4);
  std::vector<std::atomic<int>> inside(pool.workers());
  std::atomic<bool> shared{false};
  pool.run(2000, [&](std::size_t, std::size_t worker) {
    if (++inside[worker] != 1) shared = true;
    volatile double x = 0.0;
    for (int k = 0; k < 200; ++k) x = x + k;  // some work, so that calls overlap
    --inside[worker];
  });
  EXPECT_FALSE(shared.load());
}

TEST(runtime_ThreadPool, RethrowsTheLowestIndexThatThrewAfterTheOthersRan) {
  ThreadPool pool(3);
  std::atomic<int> ran{0};
  try {
    pool.run(100, [&](std::size_t i, std::size_t) {
      ++ran;
      if (i == 70 || i == 30) throw std::runtime_error("index " + std::to_string(i));
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "index 30");
  }
  EXPECT_EQ(ran.load(), 100);
  std::atomic<int> again{0};  // the pool is usable after it
  pool.run(10, [&](std::size_t, std::size_t) { ++again; });
  EXPECT_EQ(again.load(), 10);
}

TEST(runtime_ThreadPool, SharedPoolPerThreadCount) {
  EXPECT_EQ(runtime::sharedThreadPool(1), nullptr);
  EXPECT_EQ(runtime::sharedThreadPool(0), nullptr);
  ParallelFor* two = runtime::sharedThreadPool(2);
  ASSERT_NE(two, nullptr);
  EXPECT_EQ(two->workers(), 2u);
  EXPECT_EQ(runtime::sharedThreadPool(2), two);
}

// The filter's results do not depend on the thread count: the hall scenario with 1, 2 and 4
// threads, its saved state (particles, maps, candidates, weights, generator, ids) compared.
TEST(runtime_ThreadPool, FilterStateIsTheSameWith1And2And4Threads) {
  const auto frames = scenarios::simulateHall(31);
  for (const bool fs1 : {false, true}) {
    FastSlamOptions o;
    o.num_particles = 40;
    if (fs1) {
      o.proposal = FastSlam1Proposal{};
      o.association = AssociationMethod::kMaximumLikelihood;
    }
    std::vector<std::vector<std::uint8_t>> states;
    for (const std::size_t threads : {1u, 2u, 4u}) {
      ThreadPool pool(threads);
      FastSlam f(o, 17);
      f.initialise(frames[0].truth);
      std::size_t born = 0;
      for (std::size_t k = 1; k < frames.size(); ++k)
        born += f.step(frames[k - 1].odom, frames[k].odom, frames[k].z, &pool).num_initialised;
      EXPECT_GT(born, 0u);
      ByteWriter w;
      f.saveState(w);
      states.push_back(w.release());
    }
    EXPECT_EQ(states[0], states[1]) << (fs1 ? "FastSLAM 1.0" : "FastSLAM 2.0") << ": 1 and 2 threads";
    EXPECT_EQ(states[0], states[2]) << (fs1 ? "FastSLAM 1.0" : "FastSLAM 2.0") << ": 1 and 4 threads";
  }
}
