// Whole-filter scenarios (no images, no processes). The sports hall of paper 000 (16 ceiling lights
// at 6.5 m, camera 1.8 m above the floor), a closed rounded-rectangle loop at 0.27 m/s with frames
// at 1 Hz, noisy odometry (~5 %) and bearings (0.3 deg): bounds the map and pose errors with the
// Hungarian association, runs Maximum Likelihood for comparison, and checks bit-exact determinism.
// Walls of vertical lines (paper 002): FastSLAM 2.0 localisation in the true map. The scenarios are
// in slam_scenarios.h; the sweeps over many seeds that docs/design/slam-core.md quotes are
// research/slam_sweeps.cpp.
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "slam_scenarios.h"

namespace {

using namespace omnislam;
using namespace omnislam::slam;
using namespace omnislam::slam::scenarios;

// Bounds in the spirit of paper 000 (Table I: mean 0.48 m, max 1.05 m over the map; angle error
// under 0.087 rad). Our simulated errors are dominated by the scale that bearing-only SLAM takes
// from the first metres of odometry (all landmarks share it), so they vary with the seeds; the
// fixed seeds below are the first ones tried, not the best (research/slam_sweeps.cpp sweeps them).
/// Paper 000's map bars on one run of the hall: every light once, nothing spurious, map mean and
/// max error and the largest heading error within Table I's figures.
void expectMapWithinPaperBars(const RunFigures& r, std::uint64_t seed) {
  EXPECT_EQ(r.num_matched, 16) << seed;
  EXPECT_EQ(r.num_duplicates, 0) << seed;
  EXPECT_EQ(r.num_spurious, 0) << seed;
  EXPECT_LE(r.map_mean_err_m, 0.48) << seed;
  EXPECT_LE(r.map_max_err_m, 1.05) << seed;
  EXPECT_LE(r.max_theta_err_rad, 0.087) << seed;
}

TEST(slam_Scenario, HallHungarian) {
  const RunFigures r = runHall(AssociationMethod::kHungarian, 1, 2024);
  print("Hungarian seed 1", r);
  EXPECT_EQ(r.num_matched, 16);
  EXPECT_EQ(r.num_duplicates, 0);
  EXPECT_EQ(r.num_spurious, 0);
  EXPECT_LE(r.map_mean_err_m, 0.48);
  EXPECT_LE(r.map_max_err_m, 1.05);
  EXPECT_LE(r.final_pos_err_m, 0.3);  // back at the start, the loop is closed
  EXPECT_LE(r.max_theta_err_rad, 0.087);
  EXPECT_LE(r.rms_pos_err_m, 0.5);
  EXPECT_LT(r.final_pos_err_m, r.odom_final_pos_err_m);
  EXPECT_EQ(r.num_inconsistent, 0);
}

TEST(slam_Scenario, HallHungarianSeveralFilterSeeds) {
  // Like the paper's Fig. 7: the same data, several seeds of the filter.
  double sum_mean = 0.0;
  for (std::uint64_t seed = 2; seed <= 5; ++seed) {
    const RunFigures r = runHall(AssociationMethod::kHungarian, seed, 2024);
    print(("Hungarian seed " + std::to_string(seed)).c_str(), r);
    expectMapWithinPaperBars(r, seed);
    EXPECT_EQ(r.num_inconsistent, 0) << seed;
    sum_mean += r.map_mean_err_m;
  }
  EXPECT_LE(sum_mean / 4, 0.35);
}

TEST(slam_Scenario, HallMaximumLikelihood) {
  // The ML baseline maps the hall as well as the Hungarian method (the same bars; measured: 16/16, map mean 0.11-0.27
  // m). The paper's finding that ML loses loop closures does not reproduce in this hall (docs/results/slam-results.md,
  // "Hungarian vs ML").
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const RunFigures r = runHall(AssociationMethod::kMaximumLikelihood, seed, 2024);
    print(("ML seed " + std::to_string(seed)).c_str(), r);
    expectMapWithinPaperBars(r, seed);
    // ML decides each measurement alone and so at times gives two of one frame to one landmark
    // (measured: 2 per run; the joint assignment never does): the baseline is not the Hungarian
    // method under another name.
    EXPECT_GT(r.num_inconsistent, 0) << seed;
  }
}

TEST(slam_Scenario, DeterministicBitForBit) {
  FastSlamOptions o;
  FastSlam a(o, 77), b(o, 77), c(o, 78);
  runHall(AssociationMethod::kHungarian, 77, 2024, &a);
  runHall(AssociationMethod::kHungarian, 77, 2024, &b);
  runHall(AssociationMethod::kHungarian, 78, 2024, &c);
  const auto same = [](double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; };
  ASSERT_EQ(a.particles().size(), b.particles().size());
  bool differs_from_c = false;
  for (std::size_t k = 0; k < a.particles().size(); ++k) {
    const Particle& pa = a.particles()[k];
    const Particle& pb = b.particles()[k];
    EXPECT_TRUE(same(pa.pose.x_m, pb.pose.x_m) && same(pa.pose.y_m, pb.pose.y_m) &&
                same(pa.pose.theta_rad, pb.pose.theta_rad))
        << k;
    EXPECT_TRUE(same(a.particleWeights()[k], b.particleWeights()[k]));
    const auto la = pa.map.landmarks(), lb = pb.map.landmarks();
    ASSERT_EQ(la.size(), lb.size());
    for (std::size_t i = 0; i < la.size(); ++i) {
      EXPECT_EQ(la[i].id, lb[i].id);
      EXPECT_EQ(la[i].counter, lb[i].counter);
      EXPECT_EQ(std::memcmp(la[i].p_LinW_m.data(), lb[i].p_LinW_m.data(), 3 * sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(la[i].cov_LinW_m2.data(), lb[i].cov_LinW_m2.data(), 9 * sizeof(double)), 0);
    }
    EXPECT_EQ(pa.candidates.size(), pb.candidates.size());
    differs_from_c |= !same(pa.pose.x_m, c.particles()[k].pose.x_m);
  }
  EXPECT_TRUE(same(a.ess(), b.ess()));
  EXPECT_EQ(a.bestParticleIndex(), b.bestParticleIndex());
  EXPECT_TRUE(differs_from_c) << "another seed must give another run";
}

// With the true map, the FastSLAM 2.0 proposal holds azimuth-only lines to the truth: the line
// model, its Jacobians and the proposal are sound; the mapping failures come from elsewhere.
TEST(slam_Scenario, LinesFastSlam2LocalisesInTheTrueMap) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const LineRun r = runLines(roomLineOptions(), seed, true, true);
    // 28 lines at 0.1 deg: the heading is held to a fraction of a degree over 7 m (measured: final
    // position <= 0.002 m, largest heading error 0.25 deg), where dead reckoning drifts by 1.5 deg.
    EXPECT_LT(r.final_pos_err_m, 0.02) << "seed " << seed;
    EXPECT_LT(r.max_theta_err_deg, 0.5) << "seed " << seed;
  }
}

}  // namespace
