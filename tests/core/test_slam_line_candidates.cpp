// Unit tests of the candidate rules added for azimuth-only (vertical-line) landmarks seen by a
// forward camera (issue 7, MRCLAM): validity d) (perceptual range from every camera), validity e)
// (three views), the candidate likelihood restricted to the ray segment within the range, the first
// ray kept when the window is full, misses only inside the perceptual range, and the detection
// counter with a low detection probability. Defaults (all-round camera, no range) are unchanged.
// Also paper 002's 2D Gaussian triangulation error model against its closed form and sampling.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "omnislam/core/slam/candidate.h"
#include "omnislam/core/slam/fastslam.h"
#include "omnislam/core/slam/triangulation.h"

namespace {

using namespace omnislam;
using namespace omnislam::slam;

constexpr double kSigma = 0.01;  // rad

MeasMat q() { return MeasMat::Constant(1, 1, kSigma * kSigma); }

MeasVec azimuthTo(const Eigen::Vector3d& p, const Pose2& T) {
  return *predictMeasurement(LandmarkKind::kVerticalLine, p, T, Eigen::Vector3d::Zero());
}

CandidateObservation obs(const Eigen::Vector3d& p, const Pose2& T) {
  return makeObservation(LandmarkKind::kVerticalLine, T, Eigen::Vector3d::Zero(), azimuthTo(p, T), q());
}

Candidate lineCandidate() {
  Candidate c;
  c.kind = LandmarkKind::kVerticalLine;
  return c;
}

BearingMeasurement lineMeasurement(const Eigen::Vector3d& p, const Pose2& T) {
  BearingMeasurement m;
  m.kind = LandmarkKind::kVerticalLine;
  m.azimuth_rad = azimuthTo(p, T)(0);
  m.cov_rad2 = Eigen::Matrix2d::Identity() * kSigma * kSigma;
  return m;
}

TEST(LineCandidates, RangeValidityRejectsRaysCrossingAtTheCamera) {
  // Rays of two landmarks taken from (nearly) the same place cross at the camera.
  const Eigen::Vector3d A(4.0, 1.0, 0.0), B(4.0, -1.0, 0.0);
  Candidate c = lineCandidate();
  // A from the origin and B from 5 cm to the left cross 0.1 m in front of both (28 deg parallax).
  c.observations = {obs(A, {0.0, 0.0, 0.0}), obs(B, {0.0, 0.05, 0.0}), obs(A, {0.0, 0.0, 0.0})};
  c.num_associated = 3;
  CandidateOptions o;
  o.ncross_valid = 1;
  o.nz_min = 2;
  const auto unlimited = evaluateCandidate(c, o, 64.0);
  EXPECT_GT(unlimited.num_valid, 0);  // without a range nothing rejects the point at the camera
  const auto limited = evaluateCandidate(c, o, 64.0, RangeLimits{0.8});
  EXPECT_EQ(limited.num_valid, 0);
  EXPECT_FALSE(limited.ready);
  // Beyond max_range_m also invalid: a true landmark 4 m away with a 3 m limit.
  Candidate far = lineCandidate();
  far.observations = {obs(A, {0.0, -1.0, 0.0}), obs(A, {0.0, 0.0, 0.0}), obs(A, {0.0, 1.0, 0.0})};
  far.num_associated = 3;
  CandidateOptions of;
  of.ncross_valid = 1;
  of.nz_min = 2;
  EXPECT_GT(evaluateCandidate(far, of, 64.0).num_valid, 0);
  EXPECT_EQ(evaluateCandidate(far, of, 64.0, RangeLimits{0.0, 3.0}).num_valid, 0);
}

TEST(LineCandidates, ThreeViewsNeededForALine) {
  const Eigen::Vector3d L(4.0, 0.0, 0.0);
  CandidateOptions o;
  o.nz_min = 3;
  o.ncross_valid = 2;
  o.min_parallax_rad = 7.0 * kPi / 180.0;
  Candidate c = lineCandidate();
  // Two viewpoints 1 m apart (14 deg at 4 m), several rays each: valid pairs but two views only.
  c.observations = {obs(L, {0.0, -0.5, 0.0}), obs(L, {0.0, -0.5, 0.0}), obs(L, {0.0, 0.5, 0.0}),
                    obs(L, {0.0, 0.5, 0.0})};
  c.num_associated = 4;
  auto ev = evaluateCandidate(c, o, 64.0);
  EXPECT_GE(ev.num_valid, o.ncross_valid);
  EXPECT_TRUE(ev.valid_with_latest);
  EXPECT_FALSE(ev.ready);
  // A third view in between (7 deg from each) confirms the point.
  c.observations.push_back(obs(L, {0.0, 0.0, 0.0}));
  c.observations.push_back(obs(L, {0.0, 0.5, 0.0}));  // newest again from a far view
  c.num_associated = 6;
  ev = evaluateCandidate(c, o, 64.0);
  EXPECT_TRUE(ev.ready);
  EXPECT_NEAR(ev.best_p_LinW_m.x(), 4.0, 1e-6);
  EXPECT_NEAR(ev.best_p_LinW_m.y(), 0.0, 1e-6);
}

TEST(LineCandidates, LikelihoodWithoutEstimateUsesTheRaySegmentInRange) {
  // Candidate: one ray from the origin along +x. A measurement from nearly the same place in a
  // very different direction crosses that ray 0.15 m from the camera.
  Candidate c = lineCandidate();
  c.observations = {obs({3.0, 0.0, 0.0}, {0.0, 0.0, 0.0})};
  const Pose2 now{0.1, 0.05, 0.0};
  const MeasVec z_other = MeasVec::Constant(1, -kPi / 4);  // crosses the ray at (0.15, 0)
  const double ll_free = candidateLogLikelihood(c, z_other, q(), now, Eigen::Vector3d::Zero());
  const double ll_range = candidateLogLikelihood(c, z_other, q(), now, Eigen::Vector3d::Zero(), 0.8, 8.0);
  EXPECT_GT(ll_free, 0.0);               // a perfect match without a range
  EXPECT_LT(ll_range, ll_free - 100.0);  // far from any point 0.8-8 m along the ray
  // The true landmark's measurement still matches with the range.
  const MeasVec z_true = azimuthTo({3.0, 0.0, 0.0}, now);
  EXPECT_NEAR(candidateLogLikelihood(c, z_true, q(), now, Eigen::Vector3d::Zero(), 0.8, 8.0),
              candidateLogLikelihood(c, z_true, q(), now, Eigen::Vector3d::Zero()), 1e-9);
  // Rays that do not cross in front: the better end of the segment.
  const MeasVec z_back = MeasVec::Constant(1, kPi / 2);
  EXPECT_TRUE(std::isfinite(candidateLogLikelihood(c, z_back, q(), now, Eigen::Vector3d::Zero(), 0.8, 8.0)));
}

FastSlamOptions forwardOptions() {
  FastSlamOptions o;
  o.num_particles = 1;
  o.motion.trans_sigma_per_m = o.motion.lateral_sigma_per_m = o.motion.trans_sigma_per_rad = 0.0;
  o.motion.rot_sigma_per_rad = o.motion.rot_sigma_per_m = 0.0;
  o.motion.min_sigma_xy_m = 1e-6;
  o.motion.min_sigma_theta_rad = 1e-7;
  o.perception.azimuth_half_width_rad = 0.6;
  o.perception.min_range_m = 0.8;
  o.perception.max_range_m = 8.0;
  o.candidates.require_above_camera = false;
  o.candidates.nz_min = 3;
  o.candidates.ncross_valid = 3;
  return o;
}

TEST(LineCandidates, SlowSidewaysMotionStillTriangulates) {
  // The robot creeps sideways 5 mm per frame: the 8 newest rays span 4 cm (0.6 deg at 4 m), but the
  // first ray is kept, so after 1 m (14 deg) the landmark is initialised where it is.
  FastSlamOptions o = forwardOptions();
  o.candidates.max_observations = 8;
  FastSlam f(o, 3);
  const Eigen::Vector3d L(4.0, 0.5, 0.0);
  Pose2 prev{0.0, 0.0, 0.0};
  f.initialise(prev);
  for (int k = 0; k <= 200; ++k) {
    const Pose2 now{0.0, 0.005 * k, 0.0};
    f.step(prev, now, {lineMeasurement(L, now)});
    prev = now;
  }
  const auto map = f.bestMap();
  ASSERT_EQ(map.size(), 1u);
  EXPECT_NEAR(map[0].p_LinW_m.x(), 4.0, 0.05);
  EXPECT_NEAR(map[0].p_LinW_m.y(), 0.5, 0.05);
}

TEST(LineCandidates, CandidateBehindAForwardCameraIsNotMissed) {
  // A candidate seen twice, then the robot looks the other way for many frames (seeing another
  // landmark), then back: the candidate survives and is initialised. An all-round camera would
  // have missed it at every frame.
  FastSlamOptions o = forwardOptions();
  FastSlam f(o, 5);
  const Eigen::Vector3d L(4.0, 0.0, 0.0), other(-4.0, 3.0, 0.0);
  Pose2 prev{0.0, 0.0, 0.0};
  f.initialise(prev);
  auto at = [&](const Pose2& now, const Eigen::Vector3d& p) {
    f.step(prev, now, {lineMeasurement(p, now)});
    prev = now;
  };
  at({0.0, 0.0, 0.0}, L);
  at({0.0, 0.1, 0.0}, L);
  for (int k = 0; k < 30; ++k) at({0.0, 0.1, kPi}, other);  // L is behind
  for (int k = 0; k < 20; ++k) at({0.0, 0.1 + 0.06 * k, 0.0}, L);
  bool found = false;
  for (const auto& l : f.bestMap())
    if ((l.p_LinW_m.head<2>() - L.head<2>()).norm() < 0.1) found = true;
  EXPECT_TRUE(found);
}

TEST(LineCandidates, LowDetectionProbabilityKeepsTrueLandmarks) {
  // p_in = 0.3: a landmark inside the window is reported in 3 frames out of 10. With +1 / -1 it
  // would be deleted; a detection counts ceil(0.7 / 0.3) = 3, so it stays.
  FastSlamOptions o = forwardOptions();
  o.perception.detection_probability = 0.3;
  FastSlam f(o, 7);
  const Eigen::Vector3d L(4.0, 0.0, 0.0);
  Landmark prior;
  prior.id = 1;
  prior.kind = LandmarkKind::kVerticalLine;
  prior.p_LinW_m = L;
  prior.cov_LinW_m2 = Eigen::Matrix3d::Identity() * 1e-4;
  prior.counter = 1;
  Pose2 prev{0.0, 0.0, 0.0};
  f.initialise(prev, {prior});
  const Eigen::Vector3d elsewhere(4.0, 2.5, 0.0);  // another object in view, so frames exist
  for (int k = 0; k < 100; ++k) {
    const Pose2 now{0.0, 0.001 * k, 0.0};
    std::vector<BearingMeasurement> z{lineMeasurement(elsewhere, now)};
    if (k % 10 < 3) z.push_back(lineMeasurement(L, now));
    f.step(prev, now, z);
    prev = now;
  }
  bool kept = false;
  for (const auto& l : f.bestMap()) kept = kept || l.id == 1;
  EXPECT_TRUE(kept);
}

// Paper 002's 2D Gaussian error model of a triangulated line, against its closed form and against
// sampling. Two views at (-b/2, 0) and (b/2, 0) of a line at (0, d), azimuth std sigma each:
// d alpha_i / d(x, y) = (-(y - y_i), x - x_i) / r^2, so Sigma = sigma^2 (H^T H)^-1
//   = diag(sigma^2 r^4 / (2 d^2), 2 sigma^2 r^4 / b^2),  r^2 = b^2 / 4 + d^2.
TEST(LineCandidates, TriangulationCovarianceClosedFormAndSampled) {
  const double b = 0.6, d = 2.0, sigma = 0.002;  // 0.11 deg; parallax 17 deg
  const Eigen::Vector3d L(0.0, d, 0.0);
  const Pose2 T1{-b / 2, 0.0, 0.3}, T2{b / 2, 0.0, -0.2};  // headings do not matter
  const MeasMat Q = MeasMat::Constant(1, 1, sigma * sigma);
  CandidateOptions o;
  o.nz_min = 2;
  o.ncross_valid = 1;
  o.require_above_camera = false;
  o.initial_cov_diag_m2 = Eigen::Vector3d::Constant(1e-12);  // the triangulation term alone
  Candidate c = lineCandidate();
  c.observations = {makeObservation(LandmarkKind::kVerticalLine, T1, Eigen::Vector3d::Zero(), azimuthTo(L, T1), Q),
                    makeObservation(LandmarkKind::kVerticalLine, T2, Eigen::Vector3d::Zero(), azimuthTo(L, T2), Q)};
  c.num_associated = 2;
  const auto ev = evaluateCandidate(c, o, 64.0);
  ASSERT_TRUE(ev.has_best);
  const double r2 = b * b / 4 + d * d;
  const double var_x = sigma * sigma * r2 * r2 / (2 * d * d), var_y = 2 * sigma * sigma * r2 * r2 / (b * b);
  EXPECT_NEAR(ev.cov_m2(0, 0), var_x, 1e-6 * var_x);
  EXPECT_NEAR(ev.cov_m2(1, 1), var_y, 1e-6 * var_y);
  EXPECT_NEAR(ev.cov_m2(0, 1), 0.0, 1e-6 * var_x);

  // Sampled: the cross-points of noisy rays spread as the model says (within 5 %).
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0.0, sigma);
  const int N = 20000;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> pts;
  for (int i = 0; i < N; ++i) {
    const auto o1 = makeObservation(LandmarkKind::kVerticalLine, T1, Eigen::Vector3d::Zero(),
                                    MeasVec::Constant(1, azimuthTo(L, T1)(0) + n(rng)), Q);
    const auto o2 = makeObservation(LandmarkKind::kVerticalLine, T2, Eigen::Vector3d::Zero(),
                                    MeasVec::Constant(1, azimuthTo(L, T2)(0) + n(rng)), Q);
    const auto x = crossPointOfRays(o1.p_CinW_m, o1.dir_W, o2.p_CinW_m, o2.dir_W, 1e-9);
    ASSERT_TRUE(x.has_value());
    pts.push_back(x->p_XinW_m.head<2>());
    mean += pts.back();
  }
  mean /= N;
  Eigen::Matrix2d S = Eigen::Matrix2d::Zero();
  for (const auto& p : pts) S += (p - mean) * (p - mean).transpose();
  S /= N - 1;
  EXPECT_NEAR(S(0, 0), var_x, 0.05 * var_x);
  EXPECT_NEAR(S(1, 1), var_y, 0.05 * var_y);
  EXPECT_NEAR(S(0, 1) / std::sqrt(var_x * var_y), 0.0, 0.03);
  EXPECT_NEAR((mean - L.head<2>()).norm(), 0.0, 3.0 * std::sqrt(var_y / N) + 1e-4);  // unbiased to first order
}

}  // namespace
