// Tests of the batch bearing-only smoother, a translation of its problem into the product's keyframe
// graph (common/smoothing, whose factors' Jacobians are tested in tests/smoothing): the ray crossing
// against a closed form, the solution as the minimum of the header's cost written independently
// (prior, odometry, bearings, landmark priors), exact recovery from noise-free data, the robust
// kernel against outliers, the covariances against the brute-force inverse of the numerical
// information (landmark priors included), a single ray with a depth prior against its closed form,
// determinism, and the refusal of invalid problems.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "omnislam/core/angles.h"
#include "omnislam/core/slam/bearing_model.h"
#include "bearing_smoother.h"
#include "omnislam/core/slam/motion_model.h"
#include "omnislam/core/slam/random.h"
#include "omnislam/smoothing/factors.h"

namespace {

using namespace omnislam;
using namespace omnislam::slam;

TEST(slam_BearingSmoother, RaysCrossAtTheirCommonPoint) {
  const Eigen::Vector2d p(2.5, -1.5);
  std::vector<Eigen::Vector2d> c = {{0, 0}, {1, -4}, {5, 1}};
  std::vector<double> phi;
  for (const auto& ci : c) phi.push_back(std::atan2(p.y() - ci.y(), p.x() - ci.x()));
  const auto x = intersectRays2D(c, phi);
  ASSERT_TRUE(x.has_value());
  EXPECT_LT((*x - p).norm(), 1e-12);
  // Two rays crossing at right angles through the origin offset by 1 m: closed form.
  const auto y = intersectRays2D({{0, 1}, {3, 0}}, {0.0, kPi / 2});
  ASSERT_TRUE(y.has_value());
  EXPECT_NEAR(y->x(), 3.0, 1e-12);
  EXPECT_NEAR(y->y(), 1.0, 1e-12);
  // Parallel rays, or a single one: no crossing.
  EXPECT_FALSE(intersectRays2D({{0, 0}, {0, 1}}, {0.2, 0.2}).has_value());
  EXPECT_FALSE(intersectRays2D({{0, 0}}, {0.2}).has_value());
}

// A loop around six landmarks: true poses and landmarks, odometry increments with the motion model's
// covariance, bearings of every landmark within 6 m (an omnidirectional camera).
struct Scene {
  std::vector<Pose2> poses;
  std::vector<Eigen::Vector2d> landmarks;
  SmootherProblem problem;
};

Scene makeScene(double odo_noise_scale, double bearing_sigma, double outlier_fraction, std::uint64_t seed) {
  Scene s;
  Rng rng(seed);
  const int n = 120;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * kPi * i / n;
    s.poses.push_back(Pose2{3.0 * std::cos(t), 2.0 * std::sin(t), wrapAngle(t + kPi / 2)});
  }
  s.landmarks = {{0.5, 0.3}, {5.0, 0.0}, {-5.0, 0.5}, {0.0, 4.0}, {0.5, -4.0}, {-1.0, -0.5}};
  MotionNoiseOptions mn;
  mn.trans_sigma_per_sqrt_m = 0.03;
  mn.lateral_sigma_per_sqrt_m = 0.02;
  mn.rot_sigma_per_sqrt_rad = 0.05;
  mn.rot_sigma_per_sqrt_m = 0.03;
  auto& pb = s.problem;
  const Eigen::Vector3d p_CinR(0.1, 0.0, 0.0);
  Pose2 dead = s.poses[0];
  pb.poses.push_back(dead);
  for (int i = 1; i < n; ++i) {
    const Pose2 u_true = odometryIncrement(s.poses[i - 1], s.poses[i]);
    const Eigen::Matrix3d cov = incrementCovariance(u_true, mn);
    const Eigen::Vector3d w = cov.llt().matrixL() * Eigen::Vector3d(rng.normal(), rng.normal(), rng.normal());
    const Pose2 u = Pose2::fromVec(u_true.vec() + odo_noise_scale * w);
    pb.odometry.push_back({i - 1, i, u, cov});
    dead = predictPose(dead, u);
    pb.poses.push_back(dead);  // initial estimate: dead reckoning
  }
  for (const auto& l : s.landmarks) pb.landmarks_m.push_back(l + Eigen::Vector2d(0.4, -0.3));
  for (int i = 0; i < n; ++i) {
    const Pose2& x = s.poses[i];
    const Eigen::Vector2d c = x.transformFrom(p_CinR.head<2>());
    for (int j = 0; j < static_cast<int>(s.landmarks.size()); ++j) {
      const Eigen::Vector2d d = s.landmarks[j] - c;
      const double az = wrapAngle(std::atan2(d.y(), d.x()) - x.theta_rad);
      if (d.norm() > 6.0) continue;
      double z = az + bearing_sigma * rng.normal();
      if (rng.uniform01() < outlier_fraction)
        z = wrapAngle(az + (rng.uniform01() < 0.5 ? -1 : 1) * (0.1 + 0.4 * rng.uniform01()));
      pb.bearings.push_back({i, j, z, bearing_sigma > 0 ? bearing_sigma : 0.01, p_CinR});
    }
  }
  return s;
}

double positionRmse(const std::vector<Pose2>& a, const std::vector<Pose2>& b) {
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += std::pow(a[i].x_m - b[i].x_m, 2) + std::pow(a[i].y_m - b[i].y_m, 2);
  return std::sqrt(s / static_cast<double>(a.size()));
}

TEST(slam_BearingSmoother, NoiseFreeDataIsRecoveredExactly) {
  // Odometry and bearings exact; the initial landmarks 0.5 m off: the zero-cost solution is the truth.
  Scene s = makeScene(0.0, 0.0, 0.0, 1);
  for (auto& f : s.problem.odometry) f.covariance = Eigen::Vector3d(1e-4, 1e-4, 1e-4).asDiagonal();
  for (int i = 1; i < static_cast<int>(s.problem.poses.size()); ++i)  // start far from the truth
    s.problem.poses[i] = Pose2{s.poses[i].x_m + 0.3, s.poses[i].y_m - 0.2, wrapAngle(s.poses[i].theta_rad + 0.05)};
  const SmootherResult r = smoothBearingOnly(s.problem);
  ASSERT_TRUE(r.failure.empty()) << r.failure;
  EXPECT_TRUE(r.converged);
  EXPECT_LT(r.final_cost, 1e-12);
  EXPECT_LT(positionRmse(r.poses, s.poses), 1e-6);
  for (size_t j = 0; j < s.landmarks.size(); ++j) EXPECT_LT((r.landmarks_m[j] - s.landmarks[j]).norm(), 1e-6) << j;
  for (double w : r.bearing_weights) EXPECT_NEAR(w, 1.0, 1e-9);
}

// A pose at 1e300 m makes the cost infinite: no step can lower it, and it once read as converged at
// that "minimum". It is the solver's failure, with nothing returned.
TEST(slam_BearingSmoother, AnInfiniteInitialCostIsAFailureNotAMinimum) {
  Scene s = makeScene(0.0, 0.01, 0.0, 2);
  s.problem.poses[7].x_m = 1e300;
  const SmootherResult r = smoothBearingOnly(s.problem);
  EXPECT_EQ(r.failure.rfind("solver: ", 0), 0u) << r.failure;
  EXPECT_FALSE(r.converged);
  EXPECT_TRUE(r.poses.empty());
}

TEST(slam_BearingSmoother, BeatsDeadReckoningOnNoisyData) {
  Scene s = makeScene(1.0, 0.01, 0.0, 2);
  SmootherOptions ls;
  ls.cauchy_scale = 0.0;  // Gaussian noise only: the least-squares cost is the chi-square statistic
  const double dr = positionRmse(s.problem.poses, s.poses);
  const SmootherResult r = smoothBearingOnly(s.problem, ls);
  ASSERT_TRUE(r.failure.empty()) << r.failure;
  EXPECT_TRUE(r.converged);
  EXPECT_LT(r.final_cost, r.initial_cost);
  const double sm = positionRmse(r.poses, s.poses);
  EXPECT_LT(sm, 0.25 * dr) << "smoothed " << sm << " m, dead reckoning " << dr << " m";
  // With the true noise models the minimum cost is chi-square distributed with (residuals - unknowns)
  // degrees of freedom: mean dof, standard deviation sqrt(2 dof).
  const double dof = 3.0 * (1 + s.problem.odometry.size()) + s.problem.bearings.size() - 3.0 * s.problem.poses.size() -
                     2.0 * s.problem.landmarks_m.size();
  EXPECT_NEAR(r.final_cost, dof, 4.0 * std::sqrt(2.0 * dof)) << "sm " << sm << " dr " << dr;
  // The first pose is held by its prior.
  EXPECT_LT(std::hypot(r.poses[0].x_m - s.poses[0].x_m, r.poses[0].y_m - s.poses[0].y_m), 1e-2);
}

TEST(slam_BearingSmoother, CauchyKernelHoldsAgainstOutliersWhereLeastSquaresBends) {
  Scene clean = makeScene(1.0, 0.01, 0.0, 3);
  Scene dirty = makeScene(1.0, 0.01, 0.15, 3);  // same odometry noise (same draws), 15 % wrong bearings
  SmootherOptions ls;
  ls.cauchy_scale = 0.0;
  const double e_clean = positionRmse(smoothBearingOnly(clean.problem).poses, clean.poses);
  const SmootherResult robust = smoothBearingOnly(dirty.problem);
  const SmootherResult plain = smoothBearingOnly(dirty.problem, ls);
  ASSERT_TRUE(robust.failure.empty() && plain.failure.empty());
  const double e_robust = positionRmse(robust.poses, dirty.poses);
  const double e_plain = positionRmse(plain.poses, dirty.poses);
  EXPECT_LT(e_robust, 2.0 * e_clean + 0.01) << "clean " << e_clean << ", least squares " << e_plain;
  EXPECT_LT(e_robust, 0.5 * e_plain);
  // The outliers (>= 0.1 rad = 10 sigma) end with small weights, the inliers near 1.
  int low = 0;
  for (double w : robust.bearing_weights) low += w < 0.2;
  const double frac = static_cast<double>(low) / static_cast<double>(robust.bearing_weights.size());
  EXPECT_GT(frac, 0.10);
  EXPECT_LT(frac, 0.20);
}

// Whitened residuals of every factor (least squares, no kernel) at the stacked state
// (x_0, ..., x_{n-1}, l_0, ..., l_{L-1}), written from the file header's cost independently of the solver.
Eigen::VectorXd whitenedResiduals(const SmootherProblem& pb, const SmootherOptions& o, const Eigen::VectorXd& v) {
  const int n = static_cast<int>(pb.poses.size());
  auto pose = [&](int i) { return Pose2{v(3 * i), v(3 * i + 1), v(3 * i + 2)}; };
  auto landmark = [&](int j) { return Eigen::Vector3d(v(3 * n + 2 * j), v(3 * n + 2 * j + 1), 0.0); };
  std::vector<double> r;
  const Pose2 x0 = pose(0);
  r.push_back((x0.x_m - pb.poses[0].x_m) / o.prior_sigma_xy_m);
  r.push_back((x0.y_m - pb.poses[0].y_m) / o.prior_sigma_xy_m);
  r.push_back(wrapAngle(x0.theta_rad - pb.poses[0].theta_rad) / o.prior_sigma_theta_rad);
  for (const auto& f : pb.odometry) {
    const Eigen::Matrix3d U = f.covariance.inverse().llt().matrixU();  // U^T U = Sigma^-1
    const Eigen::Vector3d w = U * smoothing::odometryError(pose(f.from), pose(f.to), f.increment);
    r.insert(r.end(), w.data(), w.data() + 3);
  }
  for (const auto& f : pb.bearings) {
    const auto z = predictMeasurement(LandmarkKind::kVerticalLine, landmark(f.landmark), pose(f.pose), f.p_CinR_m);
    r.push_back(wrapAngle((*z)(0) - f.azimuth_rad) / f.sigma_rad);
  }
  for (const auto& f :
       pb.landmark_priors) {  // information = sum lambda_i v_i v_i^T: r_i = sqrt(lambda_i) v_i^T (l - mean)
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(f.information);
    const Eigen::Vector2d d = landmark(f.landmark).head<2>() - f.mean_m;
    for (int i = 0; i < 2; ++i)
      r.push_back(std::sqrt(std::max(es.eigenvalues()(i), 0.0)) * es.eigenvectors().col(i).dot(d));
  }
  return Eigen::Map<Eigen::VectorXd>(r.data(), static_cast<Eigen::Index>(r.size()));
}

TEST(slam_BearingSmoother, CovarianceIsTheInverseOfTheNumericalInformation) {
  Scene s = makeScene(1.0, 0.01, 0.0, 6);
  ASSERT_GE(s.problem.landmarks_m.size(), 2u);
  // Priors enter the information too: one along a direction only (rank 1), one full rank.
  const Eigen::Vector2d dir(std::cos(0.7), std::sin(0.7));
  s.problem.landmark_priors.push_back(
      {0, s.problem.landmarks_m[0] + Eigen::Vector2d(0.3, -0.2), dir * dir.transpose() / 0.25});
  s.problem.landmark_priors.push_back({1, s.problem.landmarks_m[1], Eigen::Matrix2d{{50.0, 10.0}, {10.0, 20.0}}});
  SmootherOptions o;
  o.cauchy_scale = 0.0;  // every weight 1: the information is J^T J of the whitened residuals
  o.compute_covariance = true;
  const SmootherResult r = smoothBearingOnly(s.problem, o);
  ASSERT_TRUE(r.failure.empty()) << r.failure;
  const int n = static_cast<int>(r.poses.size()), L = static_cast<int>(r.landmarks_m.size());
  ASSERT_TRUE(r.covariance_failure.empty()) << r.covariance_failure;
  ASSERT_EQ(static_cast<int>(r.landmark_cov_m2.size()), L);
  // Brute force: the Jacobian by central differences at the solution, the dense inverse of J^T J.
  Eigen::VectorXd v(3 * n + 2 * L);
  for (int i = 0; i < n; ++i) v.segment<3>(3 * i) = r.poses[i].vec();
  for (int j = 0; j < L; ++j) v.segment<2>(3 * n + 2 * j) = r.landmarks_m[j];
  const Eigen::VectorXd r0 = whitenedResiduals(s.problem, o, v);
  Eigen::MatrixXd J(r0.size(), v.size());
  const double h = 1e-6;
  for (Eigen::Index k = 0; k < v.size(); ++k) {
    Eigen::VectorXd a = v, b = v;
    a(k) += h;
    b(k) -= h;
    J.col(k) = (whitenedResiduals(s.problem, o, a) - whitenedResiduals(s.problem, o, b)) / (2 * h);
  }
  const Eigen::MatrixXd full = (J.transpose() * J).inverse();
  // The marginal blocks: the last pose's and each landmark's.
  const Eigen::Matrix3d pose_expected = full.block<3, 3>(3 * (n - 1), 3 * (n - 1));
  EXPECT_LT((r.last_pose_cov - pose_expected).norm(), 1e-4 * pose_expected.norm())
      << "smoother\n"
      << r.last_pose_cov << "\nbrute force\n"
      << pose_expected;
  EXPECT_TRUE(r.last_pose_cov.isApprox(r.last_pose_cov.transpose()));
  for (int j = 0; j < L; ++j) {
    const Eigen::Matrix2d expected = full.block<2, 2>(3 * n + 2 * j, 3 * n + 2 * j);
    EXPECT_LT((r.landmark_cov_m2[j] - expected).norm(), 1e-4 * expected.norm())
        << "landmark " << j << "\nsmoother\n"
        << r.landmark_cov_m2[j] << "\nbrute force\n"
        << expected;
    EXPECT_TRUE(r.landmark_cov_m2[j].isApprox(r.landmark_cov_m2[j].transpose()));
  }
  // Not requested: empty.
  o.compute_covariance = false;
  EXPECT_TRUE(smoothBearingOnly(s.problem, o).landmark_cov_m2.empty());
}

// The translation into the product's graph minimises the header's cost: at the solution the cost the
// smoother reports is the sum of squares of the residuals written here independently (prior sigmas,
// odometry covariances, bearing sigmas, camera offset, landmark priors), and its gradient vanishes.
TEST(slam_BearingSmoother, TheSolutionIsTheMinimumOfTheHeadersCost) {
  Scene s = makeScene(1.0, 0.01, 0.0, 7);
  const Eigen::Vector2d dir(std::cos(-0.4), std::sin(-0.4));
  s.problem.landmark_priors.push_back({2, s.problem.landmarks_m[2], dir * dir.transpose() / 0.09});
  SmootherOptions o;
  o.cauchy_scale = 0.0;
  o.prior_sigma_xy_m = 0.02;  // not the default: the prior's sigmas must reach the graph
  o.prior_sigma_theta_rad = 0.01;
  const SmootherResult r = smoothBearingOnly(s.problem, o);
  ASSERT_TRUE(r.failure.empty()) << r.failure;
  const int n = static_cast<int>(r.poses.size()), L = static_cast<int>(r.landmarks_m.size());
  Eigen::VectorXd v(3 * n + 2 * L);
  for (int i = 0; i < n; ++i) v.segment<3>(3 * i) = r.poses[i].vec();
  for (int j = 0; j < L; ++j) v.segment<2>(3 * n + 2 * j) = r.landmarks_m[j];
  const Eigen::VectorXd r0 = whitenedResiduals(s.problem, o, v);
  EXPECT_NEAR(r.final_cost, r0.squaredNorm(), 1e-9 * r0.squaredNorm());
  Eigen::VectorXd p(3 * n + 2 * L);
  for (int i = 0; i < n; ++i) p.segment<3>(3 * i) = s.problem.poses[i].vec();
  for (int j = 0; j < L; ++j) p.segment<2>(3 * n + 2 * j) = s.problem.landmarks_m[j];
  EXPECT_NEAR(r.initial_cost, whitenedResiduals(s.problem, o, p).squaredNorm(), 1e-9 * r.initial_cost);
  // The gradient J^T r by central differences, against the scale of its terms.
  const double h = 1e-6;
  double worst = 0.0;
  for (Eigen::Index k = 0; k < v.size(); ++k) {
    Eigen::VectorXd a = v, b = v;
    a(k) += h;
    b(k) -= h;
    const Eigen::VectorXd Jk = (whitenedResiduals(s.problem, o, a) - whitenedResiduals(s.problem, o, b)) / (2 * h);
    worst = std::max(worst, std::abs(Jk.dot(r0)) / (Jk.norm() * std::max(1.0, r0.norm())));
  }
  EXPECT_LT(worst, 1e-4);
}

// One pose held by its prior sees one landmark once: the azimuth fixes the landmark's direction, a
// prior along that ray fixes its depth. The optimum is the prior's point on the ray, and the
// covariance along the ray is the prior's variance (the azimuth adds no information along it).
TEST(slam_BearingSmoother, DepthPriorAlongASingleRayGivesItsPointAndVariance) {
  const Pose2 x{1.0, 2.0, 0.4};
  const double azimuth = 0.3, depth_m = 3.5, sigma_depth_m = 2.0;
  const Eigen::Vector2d u(std::cos(x.theta_rad + azimuth), std::sin(x.theta_rad + azimuth));
  const Eigen::Vector2d expected = Eigen::Vector2d(x.x_m, x.y_m) + depth_m * u;
  SmootherProblem pb;
  pb.poses = {x};
  pb.landmarks_m = {expected + Eigen::Vector2d(0.4, -0.9)};  // start off the ray
  pb.bearings.push_back({0, 0, azimuth, 0.01, Eigen::Vector3d::Zero()});
  pb.landmark_priors.push_back({0, expected, u * u.transpose() / (sigma_depth_m * sigma_depth_m)});
  SmootherOptions o;
  o.compute_covariance = true;
  o.cauchy_scale = 0.0;
  const SmootherResult r = smoothBearingOnly(pb, o);
  ASSERT_TRUE(r.failure.empty()) << r.failure;
  EXPECT_LT((r.landmarks_m[0] - expected).norm(), 1e-6);
  ASSERT_EQ(r.landmark_cov_m2.size(), 1u) << r.covariance_failure;
  const Eigen::Matrix2d P = r.landmark_cov_m2[0];
  EXPECT_NEAR(u.dot(P * u), sigma_depth_m * sigma_depth_m, 1e-3 * sigma_depth_m * sigma_depth_m);
  // Across the ray: the azimuth's sigma times the depth, plus the pose prior's share.
  const Eigen::Vector2d n(-u.y(), u.x());
  EXPECT_NEAR(std::sqrt(n.dot(P * n)), 0.01 * depth_m, 0.1 * 0.01 * depth_m);
}

TEST(slam_BearingSmoother, IsDeterministic) {
  Scene s = makeScene(1.0, 0.01, 0.05, 4);
  const SmootherResult a = smoothBearingOnly(s.problem), b = smoothBearingOnly(s.problem);
  ASSERT_EQ(a.poses.size(), b.poses.size());
  for (size_t i = 0; i < a.poses.size(); ++i) {
    EXPECT_EQ(a.poses[i].x_m, b.poses[i].x_m);
    EXPECT_EQ(a.poses[i].theta_rad, b.poses[i].theta_rad);
  }
  EXPECT_EQ(a.final_cost, b.final_cost);
}

TEST(slam_BearingSmoother, RefusesInvalidProblemsAndOptionsNamingTheCause) {
  Scene s = makeScene(1.0, 0.01, 0.0, 5);
  {
    SmootherProblem p = s.problem;
    p.bearings[3].landmark = 99;
    const auto r = smoothBearingOnly(p);
    EXPECT_NE(r.failure.find("bearing factor 3: landmark index 99"), std::string::npos) << r.failure;
    EXPECT_TRUE(r.poses.empty());
  }
  {
    SmootherProblem p = s.problem;
    p.odometry[7].covariance(2, 2) = -1.0;
    EXPECT_NE(smoothBearingOnly(p).failure.find("odometry factor 7: covariance"), std::string::npos);
  }
  {
    SmootherProblem p = s.problem;
    p.poses[2].x_m = std::nan("");
    EXPECT_NE(smoothBearingOnly(p).failure.find("pose 2 is not finite"), std::string::npos);
  }
  {
    SmootherProblem p = s.problem;
    p.bearings[0].sigma_rad = 0.0;
    EXPECT_NE(smoothBearingOnly(p).failure.find("sigma_rad"), std::string::npos);
  }
  {
    SmootherProblem p = s.problem;
    p.landmark_priors.push_back({42, Eigen::Vector2d::Zero(), Eigen::Matrix2d::Identity()});
    EXPECT_NE(smoothBearingOnly(p).failure.find("landmark prior 0: landmark index 42"), std::string::npos);
  }
  {
    SmootherProblem p = s.problem;
    p.landmark_priors.push_back({0, Eigen::Vector2d::Zero(), Eigen::Matrix2d{{1.0, 0.0}, {0.0, -1.0}}});
    EXPECT_NE(
        smoothBearingOnly(p).failure.find("landmark prior 0: information is not symmetric positive semi-definite"),
        std::string::npos);
  }
  SmootherOptions o;
  o.cauchy_scale = -1.0;
  EXPECT_NE(smoothBearingOnly(s.problem, o).failure.find("cauchy_scale"), std::string::npos);
  o = SmootherOptions{};
  o.relative_tolerance = 1.0;
  EXPECT_NE(smoothBearingOnly(s.problem, o).failure.find("relative_tolerance"), std::string::npos)
      << smoothBearingOnly(s.problem, o).failure;
  o.relative_tolerance = 0.5;
  EXPECT_TRUE(smoothBearingOnly(s.problem, o).failure.empty());
  EXPECT_FALSE(SmootherProblem{}.validate().empty());
}

// A landmark seen along one ray without a prior has no depth: its "covariance" came out at ~1e12
// and indefinite. It is refused with a reason; the estimate itself is still returned.
TEST(slam_BearingSmoother, NoCovarianceWhereTheFactorsLeaveADirectionFree) {
  SmootherProblem pb;
  pb.poses = {Pose2{0.0, 0.0, 0.0}, Pose2{1.0, 0.0, 0.0}};
  pb.odometry.push_back({0, 1, Pose2{1.0, 0.0, 0.0}, Eigen::Matrix3d::Identity() * 1e-4});
  pb.landmarks_m = {Eigen::Vector2d(5.0, 1.5)};
  pb.bearings.push_back({1, 0, std::atan2(1.5, 4.0), 0.01, Eigen::Vector3d::Zero()});
  SmootherOptions o;
  o.compute_covariance = true;
  const SmootherResult r = smoothBearingOnly(pb, o);
  ASSERT_TRUE(r.failure.empty()) << r.failure;
  ASSERT_EQ(r.landmarks_m.size(), 1u);
  EXPECT_TRUE(r.landmark_cov_m2.empty());
  EXPECT_NE(r.covariance_failure.find("information matrix is singular"), std::string::npos) << r.covariance_failure;
  // A second ray from the other pose fixes the depth: a covariance again, positive definite.
  pb.bearings.push_back({0, 0, std::atan2(1.5, 5.0), 0.01, Eigen::Vector3d::Zero()});
  const SmootherResult r2 = smoothBearingOnly(pb, o);
  EXPECT_TRUE(r2.covariance_failure.empty()) << r2.covariance_failure;
  ASSERT_EQ(r2.landmark_cov_m2.size(), 1u);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(r2.landmark_cov_m2[0]).eigenvalues().minCoeff(), 0.0);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(r2.last_pose_cov).eigenvalues().minCoeff(), 0.0);
}

}  // namespace
