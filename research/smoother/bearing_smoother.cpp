// Robust batch smoothing of poses and vertical-line landmarks (bearing_smoother.h): the problem's
// checks, and its translation into the product's keyframe graph, solved by smoothing::solve.
#include "bearing_smoother.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "omnislam/core/slam/types.h"
#include "omnislam/core/slam/validation.h"
#include "omnislam/smoothing/factors.h"
#include "omnislam/smoothing/smoother.h"

namespace omnislam::slam {
namespace {

bool finitePose(const Pose2& p) { return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad); }

/// The problem as a keyframe graph: poses are keyframes (id = index), landmarks vertical lines.
smoothing::Graph toGraph(const SmootherProblem& pb, const SmootherOptions& opt) {
  smoothing::Graph g;
  for (std::size_t i = 0; i < pb.poses.size(); ++i) g.keyframes.push_back({i, 0, pb.poses[i]});
  for (std::size_t j = 0; j < pb.landmarks_m.size(); ++j) {
    const Eigen::Vector2d& l = pb.landmarks_m[j];
    g.landmarks.push_back({j, LandmarkKind::kVerticalLine, Eigen::Vector3d(l.x(), l.y(), 0.0)});
  }
  for (const auto& f : pb.odometry) g.odometry.push_back({f.from, f.to, f.increment, f.covariance});
  for (const auto& f : pb.bearings) {
    BearingMeasurement z;
    z.kind = LandmarkKind::kVerticalLine;
    z.azimuth_rad = f.azimuth_rad;
    z.cov_rad2 = Eigen::Matrix2d::Identity() * (f.sigma_rad * f.sigma_rad);  // (0, 0) is used for a line
    z.p_CinR_m = f.p_CinR_m;
    g.bearings.push_back({f.pose, f.landmark, z});
  }
  const double vxy = opt.prior_sigma_xy_m * opt.prior_sigma_xy_m;
  const double vth = opt.prior_sigma_theta_rad * opt.prior_sigma_theta_rad;
  g.pose_priors.push_back({0, pb.poses[0], Eigen::Vector3d(vxy, vxy, vth).asDiagonal()});
  for (const auto& f : pb.landmark_priors) {
    Eigen::Matrix3d info = Eigen::Matrix3d::Zero();
    info.topLeftCorner<2, 2>() = f.information;
    g.landmark_priors.push_back({f.landmark, Eigen::Vector3d(f.mean_m.x(), f.mean_m.y(), 0.0), info});
  }
  return g;
}

smoothing::SolverOptions toSolverOptions(const SmootherOptions& opt) {
  smoothing::SolverOptions so;
  so.max_iterations = opt.max_iterations;
  so.bearing_loss_sigmas = opt.cauchy_scale;  // 0: no loss
  so.outlier_rounds = 0;                      // the smoother down-weights, it removes nothing
  so.function_tolerance = opt.relative_tolerance;
  so.covariances =
      opt.compute_covariance ? smoothing::LandmarkCovariance::kMarginal : smoothing::LandmarkCovariance::kNone;
  so.inflate_azimuth_near_zenith = false;  // azimuths of vertical lines: no elevation to inflate by
  return so;
}

/// The kernel weight of each bearing at the solution (0 where it was left out of the solve).
std::vector<double> bearingWeights(const smoothing::Graph& g, const smoothing::Solution& s, double c) {
  std::vector<double> w;
  w.reserve(g.bearings.size());
  for (std::size_t i = 0; i < g.bearings.size(); ++i) {
    const auto& e = g.bearings[i];
    const auto err =
        smoothing::lineAzimuthError(e.z, s.keyframe_poses[e.keyframe], s.landmarks_m[e.landmark].head<2>());
    if (!s.bearing_used[i] || !err) {
      w.push_back(0.0);
      continue;
    }
    const double r2 = *err * *err / e.z.cov_rad2(0, 0);
    w.push_back(c > 0.0 ? 1.0 / (1.0 + r2 / (c * c)) : 1.0);
  }
  return w;
}

/// The marginal covariances of the solution, or why there are none (a landmark not located: its
/// information is singular, smoothing::solve left it out).
void copyCovariances(const smoothing::Solution& s, SmootherResult& res) {
  if (!s.covariance_failure.empty()) {
    res.covariance_failure = "the information matrix is singular at the solution (" + s.covariance_failure + ")";
    return;
  }
  for (std::size_t j = 0; j < s.landmark_cov_m2.size(); ++j) {
    if (s.landmark_cov_m2[j].isZero(0.0)) {
      res.covariance_failure = "the information matrix is singular at the solution (landmark " + std::to_string(j) +
                               " is not constrained, e.g. seen along a single ray without a prior): no covariance";
      res.landmark_cov_m2.clear();
      return;
    }
    res.landmark_cov_m2.push_back(s.landmark_cov_m2[j].topLeftCorner<2, 2>());
  }
  res.last_pose_cov = s.last_pose_cov;
}

}  // namespace

std::string SmootherOptions::validate() const {
  const double big = std::numeric_limits<double>::max();  // finite: infinity is refused too
  detail::FieldChecker c;
  c.inClosed("max_iterations", max_iterations, 1, std::numeric_limits<int>::max())
      .inClosed("cauchy_scale", cauchy_scale, 0.0, big)
      .inLeftOpen("prior_sigma_xy_m", prior_sigma_xy_m, 0.0, big)
      .inLeftOpen("prior_sigma_theta_rad", prior_sigma_theta_rad, 0.0, big)
      .inOpen("relative_tolerance", relative_tolerance, 0.0, 1.0);
  return c.message();
}

std::string SmootherProblem::validate() const {
  // ": <what> index <i> out of [0, <n - 1>]", the one wording for every factor's index.
  const auto outOfRange = [](const char* what, int i, int n) {
    return std::string(": ") + what + " index " + std::to_string(i) + " out of [0, " + std::to_string(n - 1) + "]";
  };
  const int np = static_cast<int>(poses.size());
  const int nl = static_cast<int>(landmarks_m.size());
  if (np == 0) return "no poses";
  for (int i = 0; i < np; ++i)
    if (!finitePose(poses[i])) return "pose " + std::to_string(i) + " is not finite";
  for (int j = 0; j < nl; ++j)
    if (!landmarks_m[j].allFinite()) return "landmark " + std::to_string(j) + " is not finite";
  for (size_t k = 0; k < odometry.size(); ++k) {
    const auto& f = odometry[k];
    const std::string who = "odometry factor " + std::to_string(k);
    if (f.from < 0 || f.from >= np || f.to < 0 || f.to >= np || f.from == f.to)
      return who + ": pose indices " + std::to_string(f.from) + ", " + std::to_string(f.to) +
             " must be distinct and in [0, " + std::to_string(np - 1) + "]";
    if (!finitePose(f.increment) || !f.covariance.allFinite()) return who + ": not finite";
    if (!f.covariance.isApprox(f.covariance.transpose(), 1e-9) || f.covariance.llt().info() != Eigen::Success)
      return who + ": covariance is not symmetric positive definite";
  }
  for (size_t k = 0; k < bearings.size(); ++k) {
    const auto& f = bearings[k];
    const std::string who = "bearing factor " + std::to_string(k);
    if (f.pose < 0 || f.pose >= np) return who + outOfRange("pose", f.pose, np);
    if (f.landmark < 0 || f.landmark >= nl) return who + outOfRange("landmark", f.landmark, nl);
    if (!std::isfinite(f.azimuth_rad) || !f.p_CinR_m.allFinite()) return who + ": azimuth or p_CinR_m not finite";
    if (!(f.sigma_rad > 0.0) || !std::isfinite(f.sigma_rad)) return who + ": sigma_rad must be finite and > 0";
  }
  for (size_t k = 0; k < landmark_priors.size(); ++k) {
    const auto& f = landmark_priors[k];
    const std::string who = "landmark prior " + std::to_string(k);
    if (f.landmark < 0 || f.landmark >= nl) return who + outOfRange("landmark", f.landmark, nl);
    if (!f.mean_m.allFinite() || !f.information.allFinite()) return who + ": not finite";
    const Eigen::Vector2d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(f.information).eigenvalues();
    if (!f.information.isApprox(f.information.transpose(), 1e-9) || ev(0) < -1e-9 * std::max(1.0, std::abs(ev(1))))
      return who + ": information is not symmetric positive semi-definite";
  }
  return {};
}

std::optional<Eigen::Vector2d> intersectRays2D(const std::vector<Eigen::Vector2d>& centres_m,
                                               const std::vector<double>& directions_rad, double min_eigenvalue) {
  if (centres_m.size() != directions_rad.size() || centres_m.size() < 2) return std::nullopt;
  // Perpendicular distance of p from ray k: n_k . (p - c_k), n_k = (-sin phi, cos phi).
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (size_t k = 0; k < centres_m.size(); ++k) {
    const Eigen::Vector2d n(-std::sin(directions_rad[k]), std::cos(directions_rad[k]));
    A += n * n.transpose();
    b += n * n.dot(centres_m[k]);
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(A);
  if (eig.eigenvalues()(0) < min_eigenvalue * static_cast<double>(centres_m.size())) return std::nullopt;
  return A.ldlt().solve(b);
}

SmootherResult smoothBearingOnly(const SmootherProblem& pb, const SmootherOptions& opt) {
  SmootherResult res;
  if (std::string why = opt.validate(); !why.empty()) {
    res.failure = "options: " + why;
    return res;
  }
  if (std::string why = pb.validate(); !why.empty()) {
    res.failure = "problem: " + why;
    return res;
  }
  const smoothing::Graph g = toGraph(pb, opt);
  const smoothing::Solution s = smoothing::solve(g, toSolverOptions(opt));
  if (!s.ok) {
    res.failure = "solver: " + s.failure;
    return res;
  }
  res.initial_cost = 2.0 * s.initial_cost;  // Ceres' cost is half the sum of squares
  res.final_cost = 2.0 * s.final_cost;
  res.iterations = std::max(s.iterations - 1, 0);  // Ceres counts the start as iteration 0
  res.converged = res.iterations < opt.max_iterations;
  res.bearing_weights = bearingWeights(g, s, opt.cauchy_scale);
  if (opt.compute_covariance) copyCovariances(s, res);
  for (const auto& x : s.keyframe_poses) res.poses.push_back(x);
  for (const auto& l : s.landmarks_m) res.landmarks_m.push_back(l.head<2>());
  return res;
}

}  // namespace omnislam::slam
