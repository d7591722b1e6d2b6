// Tests of ray cross-points (closed forms, degeneracy) and of candidate landmarks: validity rules,
// NZ_min / NCROSS_valid, initial mean/covariance/type, and the level-2 likelihood.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstring>
#include <random>

#include "omnislam/core/slam/candidate.h"
#include "omnislam/core/slam/triangulation.h"
#include "candidate_per_pair.h"

namespace {

using namespace omnislam;
using namespace omnislam::slam;

TEST(slam_CrossPoint, IntersectingRays) {
  const Eigen::Vector3d X(3.0, 1.0, 6.5);
  const Eigen::Vector3d c1(0.0, 0.0, 1.8), c2(1.0, -0.5, 1.8);
  const auto x = crossPointOfRays(c1, (X - c1) * 3.0, c2, X - c2);  // directions need not be unit
  ASSERT_TRUE(x);
  EXPECT_NEAR((x->p_XinW_m - X).norm(), 0.0, 1e-12);
  EXPECT_NEAR(x->gap_m, 0.0, 1e-12);
  EXPECT_NEAR(x->depth1_m, (X - c1).norm(), 1e-12);
  EXPECT_NEAR(x->depth2_m, (X - c2).norm(), 1e-12);
  EXPECT_NEAR(x->parallax_rad, std::acos((X - c1).normalized().dot((X - c2).normalized())), 1e-12);
}

TEST(slam_CrossPoint, SkewRaysClosedForm) {
  // Ray 1 along +x from the origin, ray 2 along +y from (2, -1, 1): closest points (2, 0, 0) and (2, 0, 1).
  const auto x = crossPointOfRays({0, 0, 0}, {1, 0, 0}, {2, -1, 1}, {0, 1, 0});
  ASSERT_TRUE(x);
  EXPECT_NEAR((x->p_XinW_m - Eigen::Vector3d(2, 0, 0.5)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(x->gap_m, 1.0, 1e-12);
  EXPECT_NEAR(x->depth1_m, 2.0, 1e-12);
  EXPECT_NEAR(x->depth2_m, 1.0, 1e-12);
  EXPECT_NEAR(x->parallax_rad, kPi / 2, 1e-12);
  // Behind the second camera: reported, not hidden.
  const auto b = crossPointOfRays({0, 0, 0}, {1, 0, 0}, {2, 1, 1}, {0, 1, 0});
  ASSERT_TRUE(b);
  EXPECT_NEAR(b->depth2_m, -1.0, 1e-12);
}

TEST(slam_CrossPoint, RandomRaysSatisfyNormalEquations) {
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d c1(n(rng), n(rng), n(rng)), c2(n(rng), n(rng), n(rng));
    const Eigen::Vector3d b1 = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    const Eigen::Vector3d b2 = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    const auto x = crossPointOfRays(c1, b1, c2, b2);
    ASSERT_TRUE(x);
    const Eigen::Vector3d p1 = c1 + x->depth1_m * b1, p2 = c2 + x->depth2_m * b2;
    EXPECT_NEAR((p1 - p2).dot(b1), 0.0, 1e-9);  // the segment is perpendicular to both rays
    EXPECT_NEAR((p1 - p2).dot(b2), 0.0, 1e-9);
    EXPECT_NEAR((p1 - p2).norm(), x->gap_m, 1e-9);
    // Closed form of the gap between two lines: |(c1 - c2) . (b1 x b2)| / |b1 x b2|.
    EXPECT_NEAR(x->gap_m, std::abs((c1 - c2).dot(b1.cross(b2))) / b1.cross(b2).norm(), 1e-9);
  }
}

TEST(slam_CrossPoint, DegenerateParallax) {
  EXPECT_FALSE(crossPointOfRays({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}));   // parallel
  EXPECT_FALSE(crossPointOfRays({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-2, 0, 0}));  // anti-parallel
  EXPECT_FALSE(crossPointOfRays({0, 0, 0}, {0, 0, 0}, {0, 1, 0}, {1, 0, 0}));   // zero direction
  const Eigen::Vector3d b2(std::cos(1e-4), std::sin(1e-4), 0.0);
  EXPECT_TRUE(crossPointOfRays({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, b2, 0.5e-4));
  EXPECT_FALSE(crossPointOfRays({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, b2, 2e-4));  // below the threshold
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(slam_CrossPoint, DepthsAloneAreCrossPointsDepthsBitForBit) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double nan = std::nan("");
  const std::vector<double> thresholds = {1e-9, 1e-6, 1e-3, 0.1, 0.49, 0.5, 0.6, 1.2, 0.0, -1.0, nan};
  int crossings = 0, refused = 0;
  for (int i = 0; i < 40000; ++i) {
    const double t = thresholds[i % thresholds.size()];
    const Eigen::Vector3d c1(5 * u(rng), 5 * u(rng), u(rng)), c2(5 * u(rng), 5 * u(rng), u(rng));
    Eigen::Vector3d b1(u(rng), u(rng), u(rng)), b2;
    switch (i % 5) {
      case 0:  // random directions
        b2 = Eigen::Vector3d(u(rng), u(rng), u(rng));
        break;
      case 1:
      case 2: {  // a parallax near the threshold (both sides, within a few per cent)
        const Eigen::Vector3d axis = b1.unitOrthogonal();
        const double angle = (std::isfinite(t) && t > 0.0 ? t : 1e-6) * (1.0 + 0.05 * u(rng));
        b2 = Eigen::AngleAxisd(angle, axis) * b1 * (0.5 + std::abs(u(rng)));
        break;
      }
      case 3:  // near the factors of 2 of the quick test
        b2 = Eigen::AngleAxisd(
                 (std::isfinite(t) && t > 0.0 ? t : 1e-6) * (u(rng) > 0 ? 2.0 : 0.5) * (1.0 + 1e-9 * u(rng)),
                 b1.unitOrthogonal()) *
             b1;
        break;
      default:  // parallel, anti-parallel, zero, non-finite
        b2 = (i / 5) % 4 == 0   ? b1
             : (i / 5) % 4 == 1 ? Eigen::Vector3d(-b1)
             : (i / 5) % 4 == 2 ? Eigen::Vector3d::Zero()
                                : Eigen::Vector3d(nan, 0, 1);
    }
    if (i % 7 == 0) b1 = -b1;
    const auto full = crossPointOfRays(c1, b1, c2, b2, t);
    const auto depths = crossDepthsOfRays(c1, b1, c2, b2, t);
    ASSERT_EQ(full.has_value(), depths.has_value()) << "case " << i << " threshold " << t;
    if (!full) {
      ++refused;
      continue;
    }
    ++crossings;
    EXPECT_TRUE(sameBits(full->depth1_m, depths->depth1_m)) << i;
    EXPECT_TRUE(sameBits(full->depth2_m, depths->depth2_m)) << i;
  }
  EXPECT_GT(crossings, 10000);  // both outcomes are exercised
  EXPECT_GT(refused, 10000);
}

// --- Candidates ------------------------------------------------------------------------------

const Eigen::Vector3d kCam(0.0, 0.0, 1.8);

MeasMat q(double sigma_rad, int dim = 2) { return MeasMat(MeasMat::Identity(dim, dim) * sigma_rad * sigma_rad); }

// A candidate fed with exact bearings of X from poses along +x every `step_m`.
Candidate candidateAlongX(const Eigen::Vector3d& X, int n, double step_m, double x0 = 0.0,
                          LandmarkKind kind = LandmarkKind::kPoint3D) {
  Candidate c;
  c.kind = kind;
  for (int i = 0; i < n; ++i) {
    const Pose2 T{x0 + i * step_m, 0.0, 0.1 * i};
    const auto z = predictMeasurement(kind, X, T, kCam);
    c.observations.push_back(makeObservation(kind, T, kCam, *z, q(deg2rad(0.3), measurementDim(kind))));
  }
  c.num_associated = n;
  c.counter = n;
  return c;
}

TEST(slam_Candidate, ExactRaysInitialiseAtThePoint) {
  const Eigen::Vector3d X(2.0, 3.0, 6.5);
  CandidateOptions o;
  const Candidate c = candidateAlongX(X, 6, 0.5);
  const CandidateEvaluation ev = evaluateCandidate(c, o, 64.0);
  // Count the pairs whose parallax exceeds ANG_min by hand.
  int expected_valid = 0;
  bool latest = false;
  for (int a = 0; a < 6; ++a) {
    for (int b = a + 1; b < 6; ++b) {
      const Eigen::Vector3d ca(0.5 * a, 0, 1.8), cb(0.5 * b, 0, 1.8);
      if (std::acos((X - ca).normalized().dot((X - cb).normalized())) > o.min_parallax_rad) {
        ++expected_valid;
        latest |= b == 5;
      }
    }
  }
  EXPECT_EQ(ev.num_cross_points, 15);
  EXPECT_EQ(ev.num_valid, expected_valid);
  EXPECT_EQ(ev.valid_with_latest, latest);
  ASSERT_GE(expected_valid, o.ncross_valid);
  EXPECT_TRUE(ev.ready);
  EXPECT_NEAR((ev.best_p_LinW_m - X).norm(), 0.0, 1e-9);
  EXPECT_EQ(ev.type, LandmarkType::kTypeI);
  // Sigma_0 = triangulation covariance + paper's diag: larger than the diag, symmetric PD.
  EXPECT_GT(ev.cov_m2.trace(), o.initial_cov_diag_m2.sum());
  EXPECT_NEAR((ev.cov_m2 - ev.cov_m2.transpose()).norm(), 0.0, 1e-15);
  o.initial_cov_from_triangulation = false;
  const CandidateEvaluation ev2 = evaluateCandidate(c, o, 64.0);
  EXPECT_TRUE(ev2.cov_m2.isApprox(Eigen::Matrix3d(o.initial_cov_diag_m2.asDiagonal())));
}

TEST(slam_Candidate, ThresholdsNzMinAndNcrossValid) {
  const Eigen::Vector3d X(2.0, 3.0, 6.5);
  CandidateOptions o;
  Candidate c = candidateAlongX(X, 6, 0.5);
  c.num_associated = 2;  // below NZ_min = 3
  EXPECT_FALSE(evaluateCandidate(c, o, 64.0).ready);
  c.num_associated = 6;
  o.ncross_valid = 100;
  EXPECT_FALSE(evaluateCandidate(c, o, 64.0).ready);
  // Tiny baseline: no pair reaches ANG_min.
  const CandidateEvaluation small = evaluateCandidate(candidateAlongX(X, 6, 0.01), CandidateOptions{}, 64.0);
  EXPECT_EQ(small.num_valid, 0);
  EXPECT_FALSE(small.ready);
  EXPECT_FALSE(small.has_best);
  // The newest ray must take part in a valid cross-point: append a ray from a pose back at the start.
  Candidate c2 = candidateAlongX(X, 6, 0.5);
  const Pose2 T{0.0, 0.0, 0.0};
  c2.observations.push_back(makeObservation(LandmarkKind::kPoint3D, T, kCam,
                                            *predictMeasurement(LandmarkKind::kPoint3D, X, T, kCam), q(0.005)));
  c2.observations.push_back(makeObservation(LandmarkKind::kPoint3D, T, kCam,
                                            *predictMeasurement(LandmarkKind::kPoint3D, X, T, kCam), q(0.005)));
  c2.num_associated = 8;
  const CandidateEvaluation ev = evaluateCandidate(c2, CandidateOptions{}, 64.0);
  EXPECT_GE(ev.num_valid, 5);
  EXPECT_TRUE(ev.valid_with_latest);  // pairs with the far end of the baseline
}

TEST(slam_Candidate, ValidityBelowCameraAndOutlier) {
  CandidateOptions o;
  // Below the optical centre: invalid (b) unless disabled.
  const Eigen::Vector3d low(2.0, 3.0, 1.0);
  EXPECT_EQ(evaluateCandidate(candidateAlongX(low, 6, 0.5), o, 64.0).num_valid, 0);
  o.require_above_camera = false;
  EXPECT_GT(evaluateCandidate(candidateAlongX(low, 6, 0.5), o, 64.0).num_valid, 0);
  // One ray 3 degrees off: every cross-point fails c) (its probability is below P_new).
  Candidate c = candidateAlongX(Eigen::Vector3d(2.0, 3.0, 6.5), 6, 0.5);
  c.observations[2].z(0) += deg2rad(3.0);
  c.observations[2] =
      makeObservation(LandmarkKind::kPoint3D, c.observations[2].T_WtoR, kCam, c.observations[2].z, c.observations[2].Q);
  EXPECT_EQ(evaluateCandidate(c, CandidateOptions{}, 64.0).num_valid, 0);
  // With a looser P_new (Mahalanobis^2 < 1e4) the same candidate is valid again.
  EXPECT_GT(evaluateCandidate(c, CandidateOptions{}, 1e4).num_valid, 0);
}

TEST(slam_Candidate, TypeByDistance) {
  // A light 12 m to the side: initialised from > D_min = 8 m, so type II.
  const Eigen::Vector3d X(2.0, 12.0, 6.5);
  const CandidateEvaluation ev = evaluateCandidate(candidateAlongX(X, 12, 0.6), CandidateOptions{}, 64.0);
  ASSERT_TRUE(ev.has_best);
  EXPECT_EQ(ev.type, LandmarkType::kTypeII);
  CandidateOptions o;
  o.d_min_m = 20.0;
  EXPECT_EQ(evaluateCandidate(candidateAlongX(X, 12, 0.6), o, 64.0).type, LandmarkType::kTypeI);
}

TEST(slam_Candidate, RefinementReducesNoiseError) {
  std::mt19937 rng(8);
  std::normal_distribution<double> n(0.0, deg2rad(0.3));
  const Eigen::Vector3d X(3.0, 2.0, 6.5);
  double err_pair = 0, err_ref = 0;
  int count = 0;
  for (int t = 0; t < 50; ++t) {
    Candidate c = candidateAlongX(X, 12, 0.3);
    for (auto& ob : c.observations) {
      MeasVec z = ob.z;
      z(0) += n(rng);
      z(1) += n(rng);
      ob = makeObservation(LandmarkKind::kPoint3D, ob.T_WtoR, kCam, z, ob.Q);
    }
    CandidateOptions o;
    o.refine_initial_point = false;
    const auto a = evaluateCandidate(c, o, 64.0);
    o.refine_initial_point = true;
    const auto b = evaluateCandidate(c, o, 64.0);
    if (!a.ready || !b.ready) continue;
    err_pair += (a.best_p_LinW_m - X).norm();
    err_ref += (b.best_p_LinW_m - X).norm();
    ++count;
  }
  ASSERT_GT(count, 30);
  EXPECT_LT(err_ref, err_pair);
}

TEST(slam_Candidate, LevelTwoLikelihood) {
  const Eigen::Vector3d X(2.0, 3.0, 6.5);
  const Pose2 now{1.5, 0.2, 0.3};
  const MeasMat Q = q(deg2rad(0.3));
  const MeasVec z_true = *predictMeasurement(LandmarkKind::kPoint3D, X, now, kCam);
  MeasVec z_off = z_true;
  z_off(0) += deg2rad(5.0);
  // One ray: only the distance to the epipolar plane (candidate ray + current centre) is informative;
  // a bearing to a point 0.5 m off that plane is far less likely than the true one, while a bearing
  // along the plane (another depth on the candidate's ray) is as likely.
  Candidate one = candidateAlongX(X, 1, 0.5);
  const Eigen::Vector3d c0 = one.observations[0].p_CinW_m, c1 = cameraCentreInWorld(now, kCam);
  const Eigen::Vector3d nrm = (c1 - c0).cross(X - c0).normalized();
  const MeasVec z_plane_off = *predictMeasurement(LandmarkKind::kPoint3D, X + 0.5 * nrm, now, kCam);
  const MeasVec z_other_depth = *predictMeasurement(LandmarkKind::kPoint3D, c0 + 1.5 * (X - c0), now, kCam);
  const double l_true = candidateLogLikelihood(one, z_true, Q, now, kCam);
  EXPECT_GT(l_true, candidateLogLikelihood(one, z_plane_off, Q, now, kCam) + 10.0);
  EXPECT_NEAR(candidateLogLikelihood(one, z_other_depth, Q, now, kCam), l_true, 1.0);
  // Same pose as the stored ray: parallel rays -> point at infinity, still the right answer.
  const Pose2 same{0.0, 0.0, 0.0};
  const MeasVec z_same = *predictMeasurement(LandmarkKind::kPoint3D, X, same, kCam);
  EXPECT_GT(candidateLogLikelihood(one, z_same, Q, same, kCam), candidateLogLikelihood(one, z_off, Q, same, kCam));
  // With an estimate: N(z; h(X, x_t), Q + H Sigma H^T).
  Candidate est = candidateAlongX(X, 6, 0.5);
  est.has_estimate = true;
  est.estimate_W_m = X;
  est.estimate_cov_m2 = Eigen::Matrix3d::Identity() * 1e-4;
  EXPECT_GT(candidateLogLikelihood(est, z_true, Q, now, kCam), candidateLogLikelihood(est, z_off, Q, now, kCam) + 10.0);
  // Kind mismatch (dimension) is impossible.
  MeasVec z1(1);
  z1 << 0.3;
  EXPECT_EQ(candidateLogLikelihood(est, z1, q(0.005, 1), now, kCam), -std::numeric_limits<double>::infinity());
}

TEST(slam_Candidate, LikelihoodWithOnePredictionPerCandidateIsThePerPairFormBitForBit) {
  std::mt19937_64 rng(22);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<std::pair<double, double>> ranges = {{0.0, inf}, {0.3, 8.5}, {0.5, inf}, {0.0, 6.0}};
  int finite = 0, compared = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const LandmarkKind kind = trial % 2 ? LandmarkKind::kVerticalLine : LandmarkKind::kPoint3D;
    const int dim = measurementDim(kind);
    const Eigen::Vector3d cam(0.1 * u(rng), 0.1 * u(rng), 0.5 + 0.5 * u(rng));
    // A few candidates: rays from random poses to random points, some with an estimate.
    std::vector<Candidate> cands;
    for (int k = 0; k < 8; ++k) {
      Candidate c;
      c.kind = kind;
      const Eigen::Vector3d X(6 * u(rng), 6 * u(rng), 4.0 + 2 * u(rng));
      const int n = 1 + k % 3;
      for (int j = 0; j < n; ++j) {
        const Pose2 T{3 * u(rng), 3 * u(rng), 3 * u(rng)};
        const auto z = predictMeasurement(kind, X, T, cam);
        if (!z) continue;
        c.observations.push_back(makeObservation(kind, T, cam, *z, q(deg2rad(0.3 + 2.0 * std::abs(u(rng))), dim)));
      }
      c.has_estimate = k % 4 == 3 && !c.observations.empty();
      c.estimate_W_m = X + 0.2 * Eigen::Vector3d(u(rng), u(rng), u(rng));
      const Eigen::Matrix3d A = Eigen::Matrix3d::Random() * 0.1;
      c.estimate_cov_m2 = A * A.transpose() + Eigen::Matrix3d::Identity() * 1e-4;
      cands.push_back(c);
    }
    const Pose2 now_pose{3 * u(rng), 3 * u(rng), 3 * u(rng)};
    const auto [min_r, max_r] = ranges[trial % ranges.size()];
    std::vector<CandidatePrediction> predictions(cands.size());
    for (int m = 0; m < 12; ++m) {  // many measurements against the same predictions
      MeasVec z(dim);
      for (int d = 0; d < dim; ++d) z(d) = (d == 0 ? 3.1 : 1.5) * u(rng);
      if (m % 5 == 0) z(0) = kPi;  // the wrap
      const auto now = makeObservation(kind, now_pose, cam, z, q(deg2rad(0.5 + std::abs(u(rng))), dim));
      for (size_t k = 0; k < cands.size(); ++k) {
        const double ref = omnislam::testing::candidateLogLikelihoodPerPair(cands[k], now, min_r, max_r);
        const double with = candidateLogLikelihood(cands[k], now, min_r, max_r, predictions[k]);
        const double fresh = candidateLogLikelihood(cands[k], now, min_r, max_r);
        ++compared;
        if (std::isfinite(ref)) ++finite;
        EXPECT_TRUE(sameBits(ref, with)) << "trial " << trial << " candidate " << k << ": " << ref << " vs " << with;
        EXPECT_TRUE(sameBits(ref, fresh)) << "trial " << trial << " candidate " << k;
      }
    }
    // A prediction made for another pose, camera or range is remade, not reused.
    const auto moved = makeObservation(kind, Pose2{now_pose.x_m + 0.5, now_pose.y_m, now_pose.theta_rad + 0.2}, cam,
                                       MeasVec::Constant(dim, 0.2), q(0.01, dim));
    for (size_t k = 0; k < cands.size(); ++k) {
      EXPECT_TRUE(sameBits(omnislam::testing::candidateLogLikelihoodPerPair(cands[k], moved, min_r, max_r),
                           candidateLogLikelihood(cands[k], moved, min_r, max_r, predictions[k])));
      EXPECT_TRUE(sameBits(omnislam::testing::candidateLogLikelihoodPerPair(cands[k], moved, 0.0, 3.0),
                           candidateLogLikelihood(cands[k], moved, 0.0, 3.0, predictions[k])));
    }
  }
  EXPECT_GT(finite, compared / 2);
}

TEST(slam_Candidate, VerticalLineInitialisesInXY) {
  const Eigen::Vector3d X(2.0, 3.0, 0.0);
  const Candidate c = candidateAlongX(X, 8, 0.5, 0.0, LandmarkKind::kVerticalLine);
  const CandidateEvaluation ev = evaluateCandidate(c, CandidateOptions{}, 64.0);
  ASSERT_TRUE(ev.ready);
  EXPECT_NEAR((ev.best_p_LinW_m.head<2>() - X.head<2>()).norm(), 0.0, 1e-9);
}

TEST(slam_Candidate, OptionsValidate) {
  CandidateOptions o;
  EXPECT_EQ(o.validate(), "");
  o.min_parallax_rad = 4.0;
  EXPECT_NE(o.validate().find("min_parallax_rad"), std::string::npos);
  o = CandidateOptions{};
  o.max_observations = 3;  // 3 pairs < NCROSS_valid = 5
  EXPECT_NE(o.validate().find("max_observations"), std::string::npos);
}

}  // namespace
