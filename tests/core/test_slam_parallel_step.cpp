// The filter's step on an executor (FastSlam::step with a ParallelFor): the particles in another
// order, on several workers, give the same bits as one after the other (saveState compared), every
// landmark id is given once, a checkpoint taken between parallel steps continues bit for bit, and a
// throw inside the parallel part leaves the filter as it was. The thread pool itself, at 1, 2 and 4
// threads: tests/runtime/test_thread_pool.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <stdexcept>
#include <vector>

#include "omnislam/core/parallel_for.h"
#include "omnislam/core/slam/fastslam.h"
#include "slam_scenarios.h"

using namespace omnislam;
using namespace omnislam::slam;

namespace {

// Runs the indices on one thread in a scrambled order (odd indices backwards, then even ones
// forwards), on worker i % 3 of three: what a pool may do, made reproducible.
class ScrambledFor final : public ParallelFor {
 public:
  std::size_t workers() const override { return 3; }
  void run(std::size_t n, const Body& body) override {
    ++runs;
    std::vector<std::size_t> order;
    for (std::size_t i = n; i-- > 0;)
      if (i % 2 == 1) order.push_back(i);
    for (std::size_t i = 0; i < n; i += 2) order.push_back(i);
    for (std::size_t i : order) {
      if (throw_at_call >= 0 && calls++ == throw_at_call) throw std::runtime_error("injected");
      body(i, i % 3);
    }
  }
  int runs = 0;
  long calls = 0, throw_at_call = -1;
};

std::vector<std::uint8_t> stateOf(const FastSlam& f) {
  ByteWriter w;
  f.saveState(w);
  return w.release();
}

FastSlamOptions variantOptions(int variant) {
  FastSlamOptions o;
  o.num_particles = 24;
  if (variant == 1) {
    o.proposal = FastSlam1Proposal{};
    o.association = AssociationMethod::kMaximumLikelihood;
  }
  if (variant == 2) {  // the hall file's deviations: predictive pairs, weight at xhat, scale anchoring
    o.proposal = FastSlam2Proposal{stages::PredictivePairScore{}, stages::WeightAtPredictedPose{}};
    o.weight_term = ConsistencyTerm{};
    o.odometry_scale_correction = true;
    o.resample_ess_fraction = 0.5;
  }
  return o;
}

}  // namespace

TEST(slam_ParallelStep, AnyOrderAndWorkersGiveTheSameBits) {
  const auto frames = scenarios::simulateHall(21);
  for (int variant = 0; variant < 3; ++variant) {
    const FastSlamOptions o = variantOptions(variant);
    FastSlam seq(o, 9), par(o, 9);
    seq.initialise(frames[0].truth);
    par.initialise(frames[0].truth);
    ScrambledFor scrambled;
    int born = 0;
    for (std::size_t k = 1; k < frames.size(); ++k) {
      const StepResult a = seq.step(frames[k - 1].odom, frames[k].odom, frames[k].z);
      const StepResult b = par.step(frames[k - 1].odom, frames[k].odom, frames[k].z, &scrambled);
      ASSERT_EQ(a.landmark_of_measurement, b.landmark_of_measurement) << "variant " << variant << " step " << k;
      ASSERT_EQ(a.best_particle, b.best_particle) << "variant " << variant << " step " << k;
      born += a.num_initialised;
      if (k % 40 == 0) {
        ASSERT_EQ(stateOf(seq), stateOf(par)) << "variant " << variant << " step " << k;
      }
    }
    EXPECT_EQ(stateOf(seq), stateOf(par)) << "variant " << variant;
    // Per step: the drafts, the commits, the release of the particles replaced.
    EXPECT_EQ(scrambled.runs, 3 * static_cast<int>(frames.size() - 1));
    EXPECT_GT(born, 0) << "variant " << variant << ": landmarks were born (their ids were given)";
    // Every landmark id names one landmark in every particle; the newest id is below the counter.
    for (const Particle& p : par.particles()) {
      std::set<std::uint64_t> ids;
      for (const Landmark& l : p.map.landmarks()) EXPECT_TRUE(ids.insert(l.id).second) << "id " << l.id;
    }
  }
}

TEST(slam_ParallelStep, CheckpointBetweenParallelStepsContinuesBitForBit) {
  const auto frames = scenarios::simulateHall(22);
  const FastSlamOptions o = variantOptions(0);
  FastSlam f(o, 4);
  f.initialise(frames[0].truth);
  ScrambledFor scrambled;
  const std::size_t half = frames.size() / 2;
  for (std::size_t k = 1; k < half; ++k) f.step(frames[k - 1].odom, frames[k].odom, frames[k].z, &scrambled);
  const std::vector<std::uint8_t> saved = stateOf(f);
  ByteReader r(saved);
  FastSlam g = FastSlam::loadState(o, r);
  for (std::size_t k = half; k < frames.size(); ++k) {
    f.step(frames[k - 1].odom, frames[k].odom, frames[k].z, &scrambled);
    g.step(frames[k - 1].odom, frames[k].odom, frames[k].z);  // on its caller alone: the same bits
  }
  EXPECT_EQ(stateOf(f), stateOf(g));
}

TEST(slam_ParallelStep, AThrowInTheParallelPartLeavesTheFilterAsItWas) {
  const auto frames = scenarios::simulateHall(23);
  const FastSlamOptions o = variantOptions(0);
  FastSlam f(o, 6);
  f.initialise(frames[0].truth);
  for (std::size_t k = 1; k < 60; ++k) f.step(frames[k - 1].odom, frames[k].odom, frames[k].z);
  const std::vector<std::uint8_t> before = stateOf(f);
  // In the drafts (call 5), and in the commits (call M + 5): some particles have stepped then.
  for (const long at : {5L, static_cast<long>(o.num_particles) + 5}) {
    ScrambledFor failing;
    failing.throw_at_call = at;
    EXPECT_THROW(f.step(frames[59].odom, frames[60].odom, frames[60].z, &failing), std::runtime_error);
    EXPECT_EQ(stateOf(f), before) << "throw at call " << at;
  }
  // And it steps on as the filter that never failed; a throw while the replaced particles are
  // released (call 2 M + 5, after the commit) does not undo or fail the step.
  FastSlam g(o, 6);
  g.initialise(frames[0].truth);
  for (std::size_t k = 1; k < 60; ++k) g.step(frames[k - 1].odom, frames[k].odom, frames[k].z);
  ScrambledFor failing_release;
  failing_release.throw_at_call = 2L * o.num_particles + 5;
  EXPECT_NO_THROW(f.step(frames[59].odom, frames[60].odom, frames[60].z, &failing_release));
  g.step(frames[59].odom, frames[60].odom, frames[60].z);
  EXPECT_EQ(stateOf(f), stateOf(g));
  f.step(frames[60].odom, frames[61].odom, frames[61].z);
  g.step(frames[60].odom, frames[61].odom, frames[61].z);
  EXPECT_EQ(stateOf(f), stateOf(g));
}
