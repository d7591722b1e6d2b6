// The strong exception guarantee of FastSlam::step and predictOnly, by fault injection: this test
// executable replaces the global operator new with one that can be armed to throw std::bad_alloc
// at its n-th allocation. A step that fails at any point leaves the filter exactly as before it
// (poses, weights, maps, candidates, counters and the random generator), so the same step retried
// gives the same result, bit for bit, as a filter that never failed. An increment whose motion
// noise is not finite is refused the same way.
#include <gtest/gtest.h>

#include <cstdlib>
#include <new>
#include <random>
#include <vector>

#include "omnislam/core/slam/fastslam.h"

namespace {
long g_allocations = 0;
long g_fail_at = -1;  ///< the allocation (by g_allocations) that throws; < 0: none
}  // namespace

void* operator new(std::size_t n) {
  ++g_allocations;
  if (g_fail_at >= 0 && g_allocations == g_fail_at) {
    g_fail_at = -1;
    throw std::bad_alloc();
  }
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
// GCC takes free() of what operator new returned for a mismatch; here operator new is malloc.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace {

using namespace omnislam;
using namespace omnislam::slam;

const Eigen::Vector3d kCam(0.0, 0.0, 1.8);
constexpr double kSigma = 0.3 * kPi / 180.0;

/// Frame k of a straight drive past eight lights at 6.5 m, with noisy bearings.
std::vector<BearingMeasurement> frame(int k, Pose2* odom) {
  *odom = Pose2{0.3 * k, 0.0, 0.0};
  std::mt19937_64 rng(static_cast<std::uint64_t>(k) + 7);
  std::normal_distribution<double> n(0.0, kSigma);
  std::vector<BearingMeasurement> z;
  for (double x : {-2.0, 2.0, 6.0, 10.0})
    for (double y : {-3.0, 3.0}) {
      const auto p = predictMeasurement(LandmarkKind::kPoint3D, Eigen::Vector3d(x, y, 6.5), *odom, kCam);
      BearingMeasurement m;
      m.azimuth_rad = wrapAngle((*p)(0) + n(rng));
      m.elevation_rad = (*p)(1) + n(rng);
      m.cov_rad2 = Eigen::Matrix2d::Identity() * kSigma * kSigma;
      m.p_CinR_m = kCam;
      z.push_back(m);
    }
  return z;
}

void expectSame(const FastSlam& a, const FastSlam& b) {
  ASSERT_EQ(a.particles().size(), b.particles().size());
  for (std::size_t k = 0; k < a.particles().size(); ++k) {
    const Particle& p = a.particles()[k];
    const Particle& q = b.particles()[k];
    EXPECT_EQ(p.pose.x_m, q.pose.x_m) << k;
    EXPECT_EQ(p.pose.y_m, q.pose.y_m) << k;
    EXPECT_EQ(p.pose.theta_rad, q.pose.theta_rad) << k;
    EXPECT_EQ(p.log_weight, q.log_weight) << k;
    EXPECT_EQ(p.map.size(), q.map.size()) << k;
    EXPECT_EQ(p.candidates.size(), q.candidates.size()) << k;
  }
  EXPECT_EQ(a.particleWeights(), b.particleWeights());
  EXPECT_EQ(a.numSteps(), b.numSteps());
  EXPECT_EQ(a.bestParticleIndex(), b.bestParticleIndex());
  const auto ma = a.bestMap(), mb = b.bestMap();
  ASSERT_EQ(ma.size(), mb.size());
  for (std::size_t i = 0; i < ma.size(); ++i) {
    EXPECT_EQ(ma[i].id, mb[i].id);
    EXPECT_EQ(ma[i].p_LinW_m, mb[i].p_LinW_m);
    EXPECT_EQ(ma[i].counter, mb[i].counter);
  }
}

TEST(slam_FastSlamExceptions, AStepThatFailsAnywhereLeavesTheFilterAsItWas) {
  FastSlamOptions o;
  o.num_particles = 20;
  o.resample_ess_fraction = 1.0;  // resample every step: the failure can hit resampling too
  FastSlam reference(o, 3);
  reference.initialise(Pose2{});
  Pose2 prev{}, now{};
  frame(0, &prev);
  for (int k = 1; k <= 6; ++k) {  // landmarks and candidates in the maps
    const auto z = frame(k, &now);
    reference.step(prev, now, z);
    prev = now;
  }
  ASSERT_GT(reference.bestMap().size(), 0u) << "the scene must map landmarks before the failures";
  const auto z = frame(7, &now);
  // How many allocations one step makes, on a copy.
  FastSlam probe = reference;
  const long a0 = g_allocations;
  probe.step(prev, now, z);
  const long per_step = g_allocations - a0;
  ASSERT_GT(per_step, 50);
  const FastSlam expected = probe;  // the step as it should be, once

  int failures = 0;
  for (int i = 1; i <= 9; ++i) {  // fail at 1/10 .. 9/10 of the step's allocations
    FastSlam f = reference;
    g_fail_at = g_allocations + 1 + per_step * i / 10;
    bool threw = false;
    try {
      f.step(prev, now, z);
    } catch (const std::bad_alloc&) {
      threw = true;
    }
    g_fail_at = -1;
    ASSERT_TRUE(threw) << "allocation " << i << "/10 of the step did not fail";
    ++failures;
    SCOPED_TRACE("failed at " + std::to_string(i) + "/10 of the step");
    expectSame(f, reference);
    f.step(prev, now, z);  // the retry
    expectSame(f, expected);
  }
  EXPECT_EQ(failures, 9);

  // predictOnly (odometry-only steps): the same, at each of its allocations.
  FastSlam predicted = reference;
  const long p0 = g_allocations;
  predicted.predictOnly(prev, now);
  const long per_prediction = g_allocations - p0;
  ASSERT_GE(per_prediction, 1);
  for (long i = 1; i <= per_prediction; ++i) {
    FastSlam f = reference;
    g_fail_at = g_allocations + i;
    EXPECT_THROW(f.predictOnly(prev, now), std::bad_alloc) << "allocation " << i;
    g_fail_at = -1;
    expectSame(f, reference);
    EXPECT_EQ(f.posesBeforeResampling().size(), reference.posesBeforeResampling().size());
    f.predictOnly(prev, now);
    expectSame(f, predicted);
    EXPECT_EQ(f.posesBeforeResampling()[0].x_m, predicted.posesBeforeResampling()[0].x_m);
  }
}

// An odometry increment whose motion noise overflows (1e300 m: the rounding junk of a corrupted pose
// reached the filter as 1e282 m) made every particle NaN for good. It is refused now, by step() and
// by predictOnly(), and the filter is left as it was: the next good step is bit-identical to one
// taken by a filter that never saw the bad increment.
TEST(slam_FastSlamExceptions, AnIncrementWhoseNoiseIsNotFiniteIsRefusedAndChangesNothing) {
  FastSlamOptions o;
  o.num_particles = 20;
  FastSlam reference(o, 5);
  reference.initialise(Pose2{});
  Pose2 prev{}, now{};
  frame(0, &prev);
  for (int k = 1; k <= 4; ++k) {
    const auto z = frame(k, &now);
    reference.step(prev, now, z);
    prev = now;
  }
  const Pose2 wild{1e300, 0.0, 0.0};
  FastSlam f = reference;
  const auto z = frame(5, &now);
  EXPECT_THROW(f.step(prev, wild, z), std::invalid_argument);
  expectSame(f, reference);
  EXPECT_THROW(f.predictOnly(prev, wild), std::invalid_argument);
  expectSame(f, reference);
  FastSlam g = reference;
  f.step(prev, now, z);
  g.step(prev, now, z);
  expectSame(f, g);
  for (const Particle& p : f.particles()) ASSERT_TRUE(p.pose.vec().allFinite());
}

}  // namespace
