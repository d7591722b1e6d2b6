// Tests of the keyframe graph solve (smoother.h) on simulated loops: exact recovery from exact
// inputs, the least-squares cost against its chi-square distribution, wrong associations removed
// and reported, scale from a known ceiling height, the flat ceiling's height, vertical lines,
// covariances against the brute-force inverse of the information, determinism and refusals.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstring>

#include "graph_sim.h"
#include "omnislam/smoothing/factors.h"
#include "omnislam/smoothing/smoother.h"

namespace {

using namespace omnislam;
using namespace omnislam::smoothing;
using sim::SimOptions;
using sim::simulateGraph;

double maxLandmarkError(const Solution& s, const std::vector<Eigen::Vector3d>& truth, bool xy_only = false) {
  double worst = 0.0;
  for (std::size_t j = 0; j < truth.size(); ++j) {
    const Eigen::Vector3d d = s.landmarks_m[j] - truth[j];
    worst = std::max(worst, xy_only ? d.head<2>().norm() : d.norm());
  }
  return worst;
}

double maxPoseError(const Solution& s, const std::vector<Pose2>& truth) {
  double worst = 0.0;
  for (std::size_t k = 0; k < truth.size(); ++k)
    worst = std::max(worst, (s.keyframe_poses[k].vec().head<2>() - truth[k].vec().head<2>()).norm());
  return worst;
}

TEST(smoothing_Solve, ExactInputsAreRecoveredFromPerturbedStarts) {
  SimOptions o;
  o.noise = false;
  const auto sim = simulateGraph(o);
  const Solution s = solve(sim.graph);
  ASSERT_TRUE(s.ok) << s.failure;
  EXPECT_LT(maxLandmarkError(s, sim.true_landmarks), 1e-6);
  EXPECT_LT(maxPoseError(s, sim.true_poses), 1e-6);
  EXPECT_TRUE(s.removed.empty());
  EXPECT_LT(s.final_cost, 1e-12);
}

TEST(smoothing_Solve, CostAtTheOptimumFollowsItsChiSquareDistribution) {
  // 2 * cost ~ chi-square(residuals - unknowns) for Gaussian noise: the mean over seeds within 4 %.
  SimOptions o;
  o.landmark_perturbation_m = 0.2;
  double sum = 0.0, dof = 0.0;
  const int seeds = 20;
  for (int seed = 1; seed <= seeds; ++seed) {
    o.seed = static_cast<unsigned>(seed);
    const auto sim = simulateGraph(o);
    SolverOptions so;
    so.bearing_loss_sigmas = 1e6;  // least squares: the distribution holds for the plain cost
    so.outlier_rounds = 0;
    so.inflate_azimuth_near_zenith = false;  // the simulated noise is per angle
    const Solution s = solve(sim.graph, so);
    ASSERT_TRUE(s.ok) << s.failure;
    sum += 2.0 * s.final_cost;
    const double residuals = 3.0 * (sim.graph.odometry.size() + 1) + 2.0 * sim.graph.bearings.size();
    dof = residuals - 3.0 * sim.graph.keyframes.size() - 3.0 * sim.graph.landmarks.size();
  }
  EXPECT_NEAR(sum / seeds / dof, 1.0, 0.04) << "dof " << dof;
}

TEST(smoothing_Solve, WrongAssociationsAreRemovedAndReported) {
  SimOptions o;
  auto sim = simulateGraph(o);
  auto& b = sim.graph.bearings;
  // Every 12th bearing is given to another landmark: an association that slipped through.
  std::vector<int> wrong;
  for (std::size_t i = 5; i < b.size(); i += 12) {
    b[i].landmark = (b[i].landmark + 5) % static_cast<int>(sim.graph.landmarks.size());
    wrong.push_back(static_cast<int>(i));
  }
  // The oracle: the same graph without the bearings that were given wrongly.
  auto pruned = simulateGraph(o);
  for (auto it = wrong.rbegin(); it != wrong.rend(); ++it)
    pruned.graph.bearings.erase(pruned.graph.bearings.begin() + *it);
  const Solution s_pruned = solve(pruned.graph);
  const Solution s = solve(sim.graph);
  ASSERT_TRUE(s.ok && s_pruned.ok);
  int found = 0;
  for (const auto& r : s.removed) found += std::count(wrong.begin(), wrong.end(), r.bearing) > 0;
  EXPECT_EQ(found, static_cast<int>(wrong.size())) << s.removed.size() << " removed";
  EXPECT_LE(s.removed.size() - found, b.size() / 100) << "correct bearings removed";
  // With them removed the solution is the oracle's.
  double worst = 0.0;
  for (std::size_t j = 0; j < s.landmarks_m.size(); ++j)
    worst = std::max(worst, (s.landmarks_m[j] - s_pruned.landmarks_m[j]).norm());
  EXPECT_LT(worst, 1e-3);
  for (const auto& r : s.removed) EXPECT_EQ(s.bearing_used[r.bearing], 0);
}

TEST(smoothing_Solve, AKnownCeilingHeightGivesTheScaleTheOdometryGetsWrong) {
  SimOptions o;
  o.noise = false;
  o.odometry_scale = 1.04;  // the odometry 4 % long
  auto sim = simulateGraph(o);
  const Solution free = solve(sim.graph);
  sim.graph.ceiling = KnownCeilingHeight{6.5, 0.02};
  const Solution known = solve(sim.graph);
  ASSERT_TRUE(free.ok && known.ok);
  // Without the height the bearings and the odometry disagree on the scale: a compromise, off by
  // decimetres. With it the elevations fix the scale.
  EXPECT_GT(maxLandmarkError(free, sim.true_landmarks), 0.1);
  EXPECT_LT(maxLandmarkError(known, sim.true_landmarks), 0.03);
}

/// Odometry whose only per-step noise is the random walk (what KeyframeGraph keeps when it calibrates).
SimOptions randomWalkOdometry() {
  SimOptions o;
  o.motion.trans_sigma_per_m = o.motion.rot_sigma_per_m = o.motion.lateral_sigma_per_m = 0.0;
  o.motion.trans_sigma_per_rad = o.motion.rot_sigma_per_rad = 0.0;
  o.motion.trans_sigma_per_sqrt_m = 0.02;
  o.motion.rot_sigma_per_sqrt_m = 0.005;
  o.motion.rot_sigma_per_sqrt_rad = 0.02;
  return o;
}

TEST(smoothing_Solve, TheOdometrysDriftIsEstimatedWhereItIsAnUnknown) {
  // Exact bearings, an odometry that drifts 0.004 rad/m, three laps: as an unknown of the run the
  // drift is found (the calibration maps the odometry onto the motion: -0.004 rad/m), and the map is
  // no worse than with the odometry taken as measured.
  SimOptions o = randomWalkOdometry();
  o.noise = false;
  o.laps = 3;
  o.heading_drift_rad_per_m = 0.004;
  auto sim = simulateGraph(o);
  const Solution plain = solve(sim.graph);
  sim.graph.odometry_calibration = OdometryCalibrationPrior{0.01, 0.003};
  const Solution calibrated = solve(sim.graph);
  ASSERT_TRUE(plain.ok && calibrated.ok) << plain.failure << calibrated.failure;
  ASSERT_TRUE(calibrated.odometry_calibration.has_value());
  EXPECT_NEAR((*calibrated.odometry_calibration)(1), -0.004, 1e-4);
  EXPECT_NEAR((*calibrated.odometry_calibration)(0), 1.0, 1e-3);  // no scale error, none found
  std::printf("max landmark error: %.3f m as per-step noise, %.3f m calibrated (drift %.5f rad/m)\n",
              maxLandmarkError(plain, sim.true_landmarks), maxLandmarkError(calibrated, sim.true_landmarks),
              (*calibrated.odometry_calibration)(1));
  EXPECT_LE(maxLandmarkError(calibrated, sim.true_landmarks), maxLandmarkError(plain, sim.true_landmarks) + 1e-3);
}

TEST(smoothing_Solve, WithAKnownCeilingTheOdometrysScaleIsEstimatedToo) {
  SimOptions o = randomWalkOdometry();
  o.noise = false;
  o.laps = 3;
  o.odometry_scale = 1.015;
  o.heading_drift_rad_per_m = 0.004;
  auto sim = simulateGraph(o);
  sim.graph.odometry_calibration = OdometryCalibrationPrior{0.01, 0.003};
  sim.graph.ceiling = KnownCeilingHeight{6.5, 0.02};
  const Solution s = solve(sim.graph);
  ASSERT_TRUE(s.ok) << s.failure;
  EXPECT_NEAR((*s.odometry_calibration)(0), 1.0 / 1.015, 1e-3);
  EXPECT_LT(maxLandmarkError(s, sim.true_landmarks), 0.03);
}

TEST(smoothing_Solve, AFlatCeilingIsEstimatedAndTheOddLampAtAnotherHeightIsTolerated) {
  SimOptions o;
  o.landmark_perturbation_m = 0.2;
  auto sim = simulateGraph(o);
  sim.graph.ceiling = FlatCeiling{0.05};
  const Solution s = solve(sim.graph);
  ASSERT_TRUE(s.ok) << s.failure;
  ASSERT_TRUE(s.ceiling_height_m.has_value());
  EXPECT_NEAR(*s.ceiling_height_m, 6.5, 0.1);
  // A lamp 1.5 m lower (a pendant) does not pull the ceiling, and is located where it hangs: the
  // loss bounds its pull.
  o.odd_lamp_offset_m = -1.5;
  auto odd = simulateGraph(o);
  odd.graph.ceiling = FlatCeiling{0.05};
  const Solution t = solve(odd.graph);
  ASSERT_TRUE(t.ok) << t.failure;
  EXPECT_NEAR(*t.ceiling_height_m, 6.5, 0.1);
  EXPECT_LT((t.landmarks_m[4] - odd.true_landmarks[4]).norm(), 0.3);
}

TEST(smoothing_Solve, VerticalLinesAreLocatedFromAzimuthsAlone) {
  SimOptions o;
  o.kind = slam::LandmarkKind::kVerticalLine;
  o.noise = false;
  const auto sim = simulateGraph(o);
  const Solution s = solve(sim.graph);
  ASSERT_TRUE(s.ok) << s.failure;
  EXPECT_LT(maxLandmarkError(s, sim.true_landmarks, true), 1e-6);
  for (std::size_t j = 0; j < sim.true_landmarks.size(); ++j)
    EXPECT_EQ(s.landmarks_m[j].z(), sim.graph.landmarks[j].p_LinW_m.z()) << "a line's z is not estimated";
}

TEST(smoothing_Solve, CovariancesAreTheInverseOfTheInformation) {
  SimOptions o;
  o.landmark_perturbation_m = 0.1;
  auto sim = simulateGraph(o);
  SolverOptions so;
  so.bearing_loss_sigmas = 1e6;  // plain least squares: information = J^T J
  so.outlier_rounds = 0;
  so.covariances = LandmarkCovariance::kMarginal;
  const Solution s = solve(sim.graph, so);
  ASSERT_TRUE(s.ok && s.covariance_failure.empty()) << s.failure << s.covariance_failure;
  // Brute force: the dense Jacobian of every whitened residual at the solution by central differences.
  Graph at = sim.graph;
  for (std::size_t k = 0; k < at.keyframes.size(); ++k) at.keyframes[k].T_WtoR = s.keyframe_poses[k];
  for (std::size_t j = 0; j < at.landmarks.size(); ++j) at.landmarks[j].p_LinW_m = s.landmarks_m[j];
  const int K = static_cast<int>(at.keyframes.size()), L = static_cast<int>(at.landmarks.size());
  std::vector<double> x;
  for (const auto& k : at.keyframes) x.insert(x.end(), {k.T_WtoR.x_m, k.T_WtoR.y_m, k.T_WtoR.theta_rad});
  for (const auto& l : at.landmarks) x.insert(x.end(), {l.p_LinW_m.x(), l.p_LinW_m.y(), l.p_LinW_m.z()});
  auto residuals = [&](const std::vector<double>& v) {
    std::vector<double> r;
    auto pose = [&](int k) { return &v[3 * k]; };
    auto lm = [&](int j) { return &v[3 * K + 3 * j]; };
    auto eval = [&](const ceres::CostFunction& c, std::vector<const double*> p) {
      std::vector<double> out(c.num_residuals());
      EXPECT_TRUE(c.Evaluate(p.data(), out.data(), nullptr));
      r.insert(r.end(), out.begin(), out.end());
    };
    for (const auto& p : at.pose_priors) eval(PosePriorCost(p.mean, p.Sigma), {pose(p.keyframe)});
    for (const auto& e : at.odometry) eval(OdometryCost(e.u_AtoB, e.Sigma_u), {pose(e.from), pose(e.to)});
    for (const auto& e : at.bearings) {
      const slam::MeasMat S = slam::measurementCovariance(e.z, true);
      eval(PointBearingCost(e.z, Eigen::Matrix2d(S)), {pose(e.keyframe), lm(e.landmark)});
    }
    return Eigen::Map<const Eigen::VectorXd>(r.data(), static_cast<Eigen::Index>(r.size())).eval();
  };
  const Eigen::VectorXd r0 = residuals(x);
  Eigen::MatrixXd J(r0.size(), static_cast<Eigen::Index>(x.size()));
  for (std::size_t i = 0; i < x.size(); ++i) {
    auto xp = x, xm = x;
    xp[i] += 1e-6;
    xm[i] -= 1e-6;
    J.col(static_cast<Eigen::Index>(i)) = (residuals(xp) - residuals(xm)) / 2e-6;
  }
  const Eigen::MatrixXd info = J.transpose() * J;
  const Eigen::MatrixXd C = info.inverse();
  for (int j = 0; j < L; ++j) {
    const Eigen::Matrix3d Cj = C.block<3, 3>(3 * K + 3 * j, 3 * K + 3 * j);
    EXPECT_LT((s.landmark_cov_m2[j] - Cj).norm(), 1e-4 * Cj.norm()) << "landmark " << j;
  }
  const Eigen::Matrix3d Cp = C.block<3, 3>(3 * (K - 1), 3 * (K - 1));
  EXPECT_LT((s.last_pose_cov - Cp).norm(), 1e-4 * Cp.norm());
  // Given the poses: the inverse of each landmark's own block of the information.
  so.covariances = LandmarkCovariance::kGivenPoses;
  const Solution g = solve(sim.graph, so);
  ASSERT_TRUE(g.ok);
  for (int j = 0; j < L; ++j) {
    const Eigen::Matrix3d Gj = info.block<3, 3>(3 * K + 3 * j, 3 * K + 3 * j).inverse();
    EXPECT_LT((g.landmark_cov_m2[j] - Gj).norm(), 1e-4 * Gj.norm()) << "landmark " << j;
    // Knowing the poses can only make a landmark surer.
    EXPECT_LE(g.landmark_cov_m2[j].trace(), s.landmark_cov_m2[j].trace() * (1 + 1e-9));
  }
}

TEST(smoothing_Solve, SolvesAreBitForBitRepeatable) {
  SimOptions o;
  o.seed = 7;
  const auto sim = simulateGraph(o);
  const Solution a = solve(sim.graph), b = solve(sim.graph);
  ASSERT_TRUE(a.ok && b.ok);
  for (std::size_t k = 0; k < a.keyframe_poses.size(); ++k)
    EXPECT_EQ(std::memcmp(&a.keyframe_poses[k], &b.keyframe_poses[k], sizeof(Pose2)), 0);
  for (std::size_t j = 0; j < a.landmarks_m.size(); ++j) EXPECT_EQ(a.landmarks_m[j], b.landmarks_m[j]);
  EXPECT_EQ(a.final_cost, b.final_cost);
}

TEST(smoothing_Solve, InvalidGraphsAndOptionsAreRefusedNamingTheElement) {
  const auto sim = simulateGraph(SimOptions{});
  Graph g = sim.graph;
  g.bearings[3].landmark = 99;
  EXPECT_EQ(solve(g).failure, "bearing 3: index");
  g = sim.graph;
  g.odometry[2].Sigma_u(1, 1) = -1.0;
  EXPECT_EQ(solve(g).failure, "odometry 2: Sigma_u not positive definite");
  g = sim.graph;
  g.pose_priors.clear();
  EXPECT_EQ(solve(g).failure, "graph: no pose prior (the gauge)");
  g = sim.graph;
  g.keyframes[1].T_WtoR.x_m = std::nan("");
  EXPECT_EQ(solve(g).failure, "keyframe 1: pose not finite");
  g = sim.graph;
  g.landmark_priors.push_back({42, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity()});
  EXPECT_EQ(solve(g).failure, "landmark prior 0: index");
  g.landmark_priors = {{0, Eigen::Vector3d::Zero(), Eigen::Vector3d(1.0, 0.0, -1.0).asDiagonal()}};
  EXPECT_EQ(solve(g).failure, "landmark prior 0: information not symmetric positive semi-definite");
  SolverOptions so;
  so.bearing_loss_sigmas = -1.0;
  EXPECT_EQ(solve(sim.graph, so).failure, "bearing_loss_sigmas must be >= 0");
  so = SolverOptions{};
  so.outlier_probability = 0.7;
  EXPECT_EQ(solve(sim.graph, so).failure, "outlier_probability must be in (0, 0.5)");
  EXPECT_FALSE(solve(g).ok);
}

TEST(smoothing_Solve, ALandmarkSeenOnceStaysOutOfTheSolveAtItsStart) {
  auto sim = simulateGraph(SimOptions{});
  Graph& g = sim.graph;
  const Eigen::Vector3d start(3.0, 3.0, 6.0);
  g.landmarks.push_back({999, slam::LandmarkKind::kPoint3D, start});
  BearingEdge once = g.bearings.front();
  once.landmark = static_cast<int>(g.landmarks.size()) - 1;
  g.bearings.push_back(once);
  const Solution s = solve(g);
  ASSERT_TRUE(s.ok) << s.failure;
  EXPECT_EQ(s.landmarks_m.back(), start);
  EXPECT_EQ(s.bearing_used.back(), 0);
  EXPECT_TRUE(s.covariance_failure.empty()) << s.covariance_failure;
}

// A landmark seen once joins the solve when it has a prior: a depth prior along its one ray (rank 1)
// puts it at the prior's point on the ray, where the single azimuth cannot.
TEST(smoothing_Solve, ALandmarkSeenOnceWithADepthPriorIsPlacedOnItsRay) {
  const Pose2 x{1.0, 2.0, 0.4};
  const double azimuth = 0.3, depth_m = 3.5;
  const Eigen::Vector2d u(std::cos(x.theta_rad + azimuth), std::sin(x.theta_rad + azimuth));
  const Eigen::Vector2d expected = Eigen::Vector2d(x.x_m, x.y_m) + depth_m * u;
  Graph g;
  g.keyframes.push_back({0, 0, x});
  g.pose_priors.push_back({0, x, Eigen::Matrix3d::Identity() * 1e-6});
  const Eigen::Vector2d start = expected + Eigen::Vector2d(0.4, -0.9);
  g.landmarks.push_back({7, slam::LandmarkKind::kVerticalLine, Eigen::Vector3d(start.x(), start.y(), 0.0)});
  slam::BearingMeasurement z;
  z.kind = slam::LandmarkKind::kVerticalLine;
  z.azimuth_rad = azimuth;
  z.cov_rad2(0, 0) = 1e-4;
  g.bearings.push_back({0, 0, z});
  Eigen::Matrix3d info = Eigen::Matrix3d::Zero();
  info.topLeftCorner<2, 2>() = u * u.transpose() / 4.0;
  g.landmark_priors.push_back({0, Eigen::Vector3d(expected.x(), expected.y(), 0.0), info});
  const Solution s = solve(g);
  ASSERT_TRUE(s.ok) << s.failure;
  EXPECT_EQ(s.bearing_used[0], 1);
  EXPECT_LT((s.landmarks_m[0].head<2>() - expected).norm(), 1e-6);
}

}  // namespace
