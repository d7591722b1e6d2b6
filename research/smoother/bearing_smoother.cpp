// Robust batch smoothing of poses and vertical-line landmarks (bearing_smoother.h): residuals,
// Jacobians and a Levenberg-Marquardt loop on Eigen's sparse LDL^T.
#include "bearing_smoother.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <limits>

#include "omnislam/core/angles.h"
#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/types.h"
#include "omnislam/core/slam/validation.h"

namespace omnislam::slam {
namespace {

bool finitePose(const Pose2& p) { return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad); }

/// Normalised bearing error e (in sigmas), with the 1x3 pose and 1x2 landmark Jacobians of the raw
/// angle error when non-null; std::nullopt where the azimuth is undefined.
std::optional<double> bearingError(const Pose2& pose, const Eigen::Vector2d& l, const SmootherBearingFactor& f,
                                   Eigen::Matrix<double, 1, 3>* J_pose, Eigen::Matrix<double, 1, 2>* J_l) {
  MeasJac Jp, Jl;
  const auto z = predictMeasurement(LandmarkKind::kVerticalLine, Eigen::Vector3d(l.x(), l.y(), 0.0), pose, f.p_CinR_m,
                                    J_pose ? &Jp : nullptr, J_l ? &Jl : nullptr);
  if (!z) return std::nullopt;
  if (J_pose) *J_pose = Jp.row(0);
  if (J_l) *J_l = Jl.row(0).head<2>();
  return wrapAngle((*z)(0) - f.azimuth_rad) / f.sigma_rad;
}

double robustCost(double e, double c) { return c > 0.0 ? c * c * std::log1p(e * e / (c * c)) : e * e; }
double robustWeight(double e, double c) { return c > 0.0 ? 1.0 / (1.0 + e * e / (c * c)) : 1.0; }

struct Layout {
  int num_poses = 0;
  int pose(int i) const { return 3 * i; }
  int landmark(int j) const { return 3 * num_poses + 2 * j; }
};

struct State {
  std::vector<Pose2> poses;
  std::vector<Eigen::Vector2d> landmarks;
};

Eigen::Vector3d priorResidual(const Pose2& p, const Pose2& prior) {
  return {p.x_m - prior.x_m, p.y_m - prior.y_m, wrapAngle(p.theta_rad - prior.theta_rad)};
}

double totalCost(const SmootherProblem& pb, const State& s, const Eigen::Matrix3d& prior_info,
                 const std::vector<Eigen::Matrix3d>& odo_info, double c) {
  const Eigen::Vector3d r0 = priorResidual(s.poses[0], pb.poses[0]);
  double cost = r0.dot(prior_info * r0);
  for (size_t k = 0; k < pb.odometry.size(); ++k) {
    const auto& f = pb.odometry[k];
    const Eigen::Vector3d r = odometryResidual(s.poses[f.from], s.poses[f.to], f.increment);
    cost += r.dot(odo_info[k] * r);
  }
  for (const auto& f : pb.bearings) {
    const auto e = bearingError(s.poses[f.pose], s.landmarks[f.landmark], f, nullptr, nullptr);
    if (e) cost += robustCost(*e, c);
  }
  for (const auto& f : pb.landmark_priors) {
    const Eigen::Vector2d r = s.landmarks[f.landmark] - f.mean_m;
    cost += r.dot(f.information * r);
  }
  return cost;
}

/// The normal equations H dx = -g of the re-weighted (IRLS) problem at s: H = J^T W J, g = J^T W r.
void normalEquations(const SmootherProblem& pb, const State& s, const Layout& lay, int n,
                     const Eigen::Matrix3d& prior_info, const std::vector<Eigen::Matrix3d>& odo_info, double c,
                     Eigen::SparseMatrix<double>& H, Eigen::VectorXd& g) {
  std::vector<Eigen::Triplet<double>> trip;
  g = Eigen::VectorXd::Zero(n);
  auto add = [&](int row0, int col0, const auto& block) {
    for (int a = 0; a < block.rows(); ++a)
      for (int b = 0; b < block.cols(); ++b) trip.emplace_back(row0 + a, col0 + b, block(a, b));
  };
  {
    const Eigen::Vector3d r = priorResidual(s.poses[0], pb.poses[0]);
    add(0, 0, prior_info);
    g.segment<3>(0) += prior_info * r;
  }
  for (size_t k = 0; k < pb.odometry.size(); ++k) {
    const auto& f = pb.odometry[k];
    Eigen::Matrix3d Ja, Jb;
    const Eigen::Vector3d r = odometryResidual(s.poses[f.from], s.poses[f.to], f.increment, &Ja, &Jb);
    const int ia = lay.pose(f.from), ib = lay.pose(f.to);
    const Eigen::Matrix3d WJa = odo_info[k] * Ja, WJb = odo_info[k] * Jb;
    add(ia, ia, Ja.transpose() * WJa);
    add(ia, ib, Ja.transpose() * WJb);
    add(ib, ia, Jb.transpose() * WJa);
    add(ib, ib, Jb.transpose() * WJb);
    g.segment<3>(ia) += Ja.transpose() * odo_info[k] * r;
    g.segment<3>(ib) += Jb.transpose() * odo_info[k] * r;
  }
  for (const auto& f : pb.bearings) {
    Eigen::Matrix<double, 1, 3> Jp;
    Eigen::Matrix<double, 1, 2> Jl;
    const auto e = bearingError(s.poses[f.pose], s.landmarks[f.landmark], f, &Jp, &Jl);
    if (!e) continue;
    const double w = robustWeight(*e, c) / (f.sigma_rad * f.sigma_rad);
    const double r = *e * f.sigma_rad;
    const int ip = lay.pose(f.pose), il = lay.landmark(f.landmark);
    add(ip, ip, w * Jp.transpose() * Jp);
    add(ip, il, w * Jp.transpose() * Jl);
    add(il, ip, w * Jl.transpose() * Jp);
    add(il, il, w * Jl.transpose() * Jl);
    g.segment<3>(ip) += w * r * Jp.transpose();
    g.segment<2>(il) += w * r * Jl.transpose();
  }
  for (const auto& f : pb.landmark_priors) {
    const int il = lay.landmark(f.landmark);
    add(il, il, f.information);
    g.segment<2>(il) += f.information * (s.landmarks[f.landmark] - f.mean_m);
  }
  H.resize(n, n);
  H.setFromTriplets(trip.begin(), trip.end());
}

}  // namespace

std::string SmootherOptions::validate() const {
  const double big = std::numeric_limits<double>::max();  // finite: infinity is refused too
  detail::FieldChecker c;
  c.inClosed("max_iterations", max_iterations, 1, std::numeric_limits<int>::max())
      .inClosed("cauchy_scale", cauchy_scale, 0.0, big)
      .inLeftOpen("prior_sigma_xy_m", prior_sigma_xy_m, 0.0, big)
      .inLeftOpen("prior_sigma_theta_rad", prior_sigma_theta_rad, 0.0, big)
      .inOpen("initial_lambda", initial_lambda, 0.0, kMaxLambda)  // at kMaxLambda no step is tried
      .inClosed("relative_tolerance", relative_tolerance, 0.0, big);
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

Eigen::Vector3d odometryResidual(const Pose2& a, const Pose2& b, const Pose2& increment, Eigen::Matrix3d* J_r_a,
                                 Eigen::Matrix3d* J_r_b) {
  const double c = std::cos(a.theta_rad), s = std::sin(a.theta_rad);
  const double dx = b.x_m - a.x_m, dy = b.y_m - a.y_m;
  const Eigen::Vector3d r(c * dx + s * dy - increment.x_m, -s * dx + c * dy - increment.y_m,
                          wrapAngle(b.theta_rad - a.theta_rad - increment.theta_rad));
  if (J_r_a) *J_r_a << -c, -s, -s * dx + c * dy, s, -c, -c * dx - s * dy, 0.0, 0.0, -1.0;
  if (J_r_b) *J_r_b << c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0;
  return r;
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

namespace {

// The weighted least-squares problem of smoothBearingOnly with its fixed weights, and the solver's
// work space (the sparse pattern is analysed anew at every solve).
struct Solver {
  const SmootherProblem& pb;
  const SmootherOptions& opt;
  Layout lay;
  int n;     ///< unknowns
  double c;  ///< Cauchy scale
  Eigen::Matrix3d prior_info;
  std::vector<Eigen::Matrix3d> odo_info;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
  Eigen::SparseMatrix<double> H;
  Eigen::VectorXd g;

  Solver(const SmootherProblem& p, const SmootherOptions& o)
      : pb(p),
        opt(o),
        lay{static_cast<int>(p.poses.size())},
        n(lay.landmark(static_cast<int>(p.landmarks_m.size()))),
        c(o.cauchy_scale) {
    prior_info = Eigen::Vector3d(1.0 / (opt.prior_sigma_xy_m * opt.prior_sigma_xy_m),
                                 1.0 / (opt.prior_sigma_xy_m * opt.prior_sigma_xy_m),
                                 1.0 / (opt.prior_sigma_theta_rad * opt.prior_sigma_theta_rad))
                     .asDiagonal();
    odo_info.reserve(pb.odometry.size());
    for (const auto& f : pb.odometry) odo_info.push_back(f.covariance.inverse());
  }
  double cost(const State& s) const { return totalCost(pb, s, prior_info, odo_info, c); }

  // s moved by the step dx (headings wrapped).
  State moved(const State& s, const Eigen::VectorXd& dx) const {
    State t = s;
    for (size_t i = 0; i < t.poses.size(); ++i) {
      const int ip = lay.pose(static_cast<int>(i));
      t.poses[i] =
          Pose2{t.poses[i].x_m + dx(ip), t.poses[i].y_m + dx(ip + 1), wrapAngle(t.poses[i].theta_rad + dx(ip + 2))};
    }
    for (size_t j = 0; j < t.landmarks.size(); ++j) t.landmarks[j] += dx.segment<2>(lay.landmark(static_cast<int>(j)));
    return t;
  }

  // One Levenberg-Marquardt iteration: lambda is raised until a step lowers the cost. False when no
  // step does (at a minimum to working precision); `converged` when the accepted step's relative
  // drop is below the tolerance.
  bool iterate(State& s, double& cost_now, double& lambda, bool& converged) {
    normalEquations(pb, s, lay, n, prior_info, odo_info, c, H, g);
    const Eigen::VectorXd diag = H.diagonal();
    while (lambda < SmootherOptions::kMaxLambda) {
      Eigen::SparseMatrix<double> Hd = H;
      // A landmark seen only at rejected (undefined) bearings has a zero diagonal: keep it solvable.
      for (int k = 0; k < n; ++k) Hd.coeffRef(k, k) += lambda * diag(k) + 1e-12;
      // The pattern is analysed every time: a bearing whose azimuth becomes undefined drops its block.
      ldlt.compute(Hd);
      if (ldlt.info() != Eigen::Success) {
        lambda *= 10.0;
        continue;
      }
      State t = moved(s, ldlt.solve(-g));
      const double new_cost = cost(t);
      if (std::isfinite(new_cost) && new_cost < cost_now) {
        const double drop = (cost_now - new_cost) / std::max(cost_now, 1e-300);
        s = std::move(t);
        cost_now = new_cost;
        lambda = std::max(lambda / 3.0, 1e-12);
        if (drop < opt.relative_tolerance) converged = true;
        return true;
      }
      lambda *= 5.0;
    }
    return false;
  }

  // The marginal covariance of the last pose and the landmarks at s, or the reason there is none.
  void covariance(const State& s, SmootherResult& res) {
    normalEquations(pb, s, lay, n, prior_info, odo_info, c, H, g);
    for (int k = 0; k < n; ++k) H.coeffRef(k, k) += 1e-12;  // as in the steps: unobserved landmarks stay solvable
    ldlt.compute(H);
    // A direction the factors do not constrain (a landmark seen along one ray only, without a
    // prior) leaves a pivot at about the 1e-12 added above: its "covariance" would be ~1e12 and
    // indefinite. Refuse it rather than return it; 1e-9 is an sd of ~3e4 m or rad.
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-9)) {
      res.covariance_failure =
          "the information matrix is singular at the solution (a landmark or pose that the "
          "factors do not constrain, e.g. seen along a single ray): no covariance";
      return;
    }
    const int nl = static_cast<int>(pb.landmarks_m.size());
    std::vector<int> idx;
    for (int a = 0; a < 3; ++a) idx.push_back(lay.pose(lay.num_poses - 1) + a);
    for (int j = 0; j < nl; ++j)
      for (int a = 0; a < 2; ++a) idx.push_back(lay.landmark(j) + a);
    const int m = static_cast<int>(idx.size());
    Eigen::MatrixXd E = Eigen::MatrixXd::Zero(n, m);
    for (int k = 0; k < m; ++k) E(idx[k], k) = 1.0;
    const Eigen::MatrixXd cols = ldlt.solve(E);
    res.covariance.resize(m, m);
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b) res.covariance(a, b) = 0.5 * (cols(idx[a], b) + cols(idx[b], a));
  }
};

}  // namespace

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
  Solver solver(pb, opt);
  State s{pb.poses, pb.landmarks_m};
  double cost = solver.cost(s);
  res.initial_cost = cost;
  // A cost that is not finite (a pose at 1e300 m) accepts no step, which read as "at a minimum": the
  // problem is refused instead, and nothing is solved.
  if (!std::isfinite(cost)) {
    res.failure = "the initial cost is not finite (a pose, landmark or factor too large to solve)";
    return res;
  }
  double lambda = opt.initial_lambda;
  for (int it = 0; it < opt.max_iterations && !res.converged; ++it) {
    res.iterations = it + 1;
    if (!solver.iterate(s, cost, lambda, res.converged)) res.converged = true;  // no step lowers the cost
  }
  res.final_cost = cost;
  if (opt.compute_covariance) solver.covariance(s, res);
  res.bearing_weights.reserve(pb.bearings.size());
  for (const auto& f : pb.bearings) {
    const auto e = bearingError(s.poses[f.pose], s.landmarks[f.landmark], f, nullptr, nullptr);
    res.bearing_weights.push_back(e ? robustWeight(*e, opt.cauchy_scale) : 0.0);
  }
  res.poses = std::move(s.poses);
  res.landmarks_m = std::move(s.landmarks);
  return res;
}

}  // namespace omnislam::slam
