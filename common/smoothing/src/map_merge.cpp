// The merge of two registered maps (map_merge.h): the joint solve of T_AB and the fused lamps on
// Ceres, its covariances, the merged list with unique ids.
#include "omnislam/smoothing/map_merge.h"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "omnislam/smoothing/factors.h"

namespace omnislam::smoothing {

Eigen::Vector3d lampInMapBError(const Pose2& T_AB, const Eigen::Vector3d& p_LinA_m, const Eigen::Vector3d& b_LinB_m,
                                Eigen::Matrix3d* J_e_T, Eigen::Matrix3d* J_e_p) {
  const double c = std::cos(T_AB.theta_rad), s = std::sin(T_AB.theta_rad);
  const Eigen::Vector2d d(p_LinA_m.x() - T_AB.x_m, p_LinA_m.y() - T_AB.y_m);
  const Eigen::Vector3d q(c * d.x() + s * d.y(), -s * d.x() + c * d.y(), p_LinA_m.z());  // T_AB^-1(p)
  if (J_e_T) {
    *J_e_T << -c, -s, -s * d.x() + c * d.y(),  //
        s, -c, -c * d.x() - s * d.y(),         //
        0.0, 0.0, 0.0;
  }
  if (J_e_p) {
    *J_e_p << c, s, 0.0,  //
        -s, c, 0.0,       //
        0.0, 0.0, 1.0;
  }
  return q - b_LinB_m;
}

LampInMapBCost::LampInMapBCost(const Eigen::Vector3d& b_LinB_m, const Eigen::Matrix3d& Sigma)
    : b_(b_LinB_m), W_(whitener<3>(Sigma).value_or(Eigen::Matrix3d::Zero())) {}

bool LampInMapBCost::Evaluate(double const* const* params, double* residuals, double** jacobians) const {
  const Pose2 T{params[0][0], params[0][1], params[0][2]};
  const Eigen::Map<const Eigen::Vector3d> p(params[1]);
  Eigen::Matrix3d J_T, J_p;
  const Eigen::Vector3d e = lampInMapBError(T, p, b_, &J_T, &J_p);
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = W_ * e;
  using RowMajor3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
  if (jacobians && jacobians[0]) Eigen::Map<RowMajor3>{jacobians[0]} = W_ * J_T;
  if (jacobians && jacobians[1]) Eigen::Map<RowMajor3>{jacobians[1]} = W_ * J_p;
  return true;
}

namespace {

/// blockdiag(R(theta), 1): a vector or covariance of B's frame turned into A's.
Eigen::Matrix3d rotation3(const Pose2& T_AB) {
  const double c = std::cos(T_AB.theta_rad), s = std::sin(T_AB.theta_rad);
  Eigen::Matrix3d R;
  R << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
  return R;
}

/// d T_AB(b) / d T_AB (3x3, z row zero).
Eigen::Matrix3d movedLampJacobian(const Pose2& T_AB, const Eigen::Vector3d& b) {
  const double c = std::cos(T_AB.theta_rad), s = std::sin(T_AB.theta_rad);
  Eigen::Matrix3d J;
  J << 1.0, 0.0, -s * b.x() - c * b.y(), 0.0, 1.0, c * b.x() - s * b.y(), 0.0, 0.0, 0.0;
  return J;
}

/// The fused lamp with T_AB held: the information-weighted mean and the inverse information sum.
void informationFusion(const slam::Landmark& a, const slam::Landmark& b, const Pose2& T, Eigen::Vector3d& p,
                       Eigen::Matrix3d& cov) {
  const Eigen::Matrix3d R = rotation3(T);
  const Eigen::Matrix3d La = a.cov_LinW_m2.inverse(), Lb = (R * b.cov_LinW_m2 * R.transpose()).inverse();
  cov = (La + Lb).inverse();
  cov = 0.5 * (cov + cov.transpose());
  p = cov * (La * a.p_LinW_m + Lb * slam::transformLamp(T, b.p_LinW_m));
}

struct Pairs {
  std::vector<int> k_of_a;  ///< per landmark of A: its inlier's index, or -1
  std::vector<int> b_of_k;  ///< per inlier: its landmark of B
  std::vector<char> matched_b;
};

Pairs checkedPairs(const std::vector<slam::Landmark>& A, const std::vector<slam::Landmark>& B,
                   const std::vector<std::pair<int, int>>& inliers) {
  Pairs p{std::vector<int>(A.size(), -1), {}, std::vector<char>(B.size(), 0)};
  for (const auto& [a, b] : inliers) {
    if (a < 0 || b < 0 || a >= static_cast<int>(A.size()) || b >= static_cast<int>(B.size()) ||
        A[static_cast<std::size_t>(a)].kind != slam::LandmarkKind::kPoint3D ||
        B[static_cast<std::size_t>(b)].kind != slam::LandmarkKind::kPoint3D ||
        p.k_of_a[static_cast<std::size_t>(a)] >= 0 || p.matched_b[static_cast<std::size_t>(b)])
      throw std::invalid_argument("mergeMaps: an inlier pair is out of range, repeated or not of two points");
    p.k_of_a[static_cast<std::size_t>(a)] = static_cast<int>(p.b_of_k.size());
    p.b_of_k.push_back(b);
    p.matched_b[static_cast<std::size_t>(b)] = 1;
  }
  return p;
}

/// The joint solve: T (in/out) and the fused lamps p (in/out, per inlier); their covariances when it
/// converged and the information is full rank. False (and `why`) otherwise.
bool jointSolve(const std::vector<slam::Landmark>& A, const std::vector<slam::Landmark>& B,
                const std::vector<std::pair<int, int>>& inliers, bool hold_T, double T[3],
                std::vector<Eigen::Vector3d>& p, Eigen::Matrix3d& cov_T, std::vector<Eigen::Matrix3d>& cov_p,
                std::string& why) {
  ceres::Problem pb;
  for (std::size_t k = 0; k < inliers.size(); ++k) {
    const slam::Landmark& a = A[static_cast<std::size_t>(inliers[k].first)];
    const slam::Landmark& b = B[static_cast<std::size_t>(inliers[k].second)];
    pb.AddResidualBlock(new LandmarkPriorCost<3>(a.p_LinW_m, a.cov_LinW_m2.inverse()), nullptr, p[k].data());
    pb.AddResidualBlock(new LampInMapBCost(b.p_LinW_m, b.cov_LinW_m2), nullptr, T, p[k].data());
  }
  if (hold_T) pb.SetParameterBlockConstant(T);
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_SCHUR;
  so.max_num_iterations = 100;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &pb, &summary);
  if (summary.termination_type != ceres::CONVERGENCE || !std::isfinite(summary.final_cost)) {
    why = "the joint solve did not converge (" + summary.message + ")";
    return false;
  }
  ceres::Covariance::Options co;
  co.num_threads = 1;
  ceres::Covariance cov(co);
  std::vector<std::pair<const double*, const double*>> wanted;
  if (!hold_T) wanted.emplace_back(T, T);
  for (auto& q : p) wanted.emplace_back(q.data(), q.data());
  if (!cov.Compute(wanted, &pb)) {
    why = "the joint solve's information is rank deficient";
    return false;
  }
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> C;
  if (!hold_T) cov.GetCovarianceBlock(T, T, C.data()), cov_T = C;
  for (std::size_t k = 0; k < p.size(); ++k) cov.GetCovarianceBlock(p[k].data(), p[k].data(), C.data()), cov_p[k] = C;
  return true;
}

}  // namespace

namespace {

/// The point landmarks with extra_sigma_m^2 added to their horizontal variances.
std::vector<slam::Landmark> inflated(std::vector<slam::Landmark> map, double extra_sigma_m) {
  for (slam::Landmark& l : map)
    if (l.kind == slam::LandmarkKind::kPoint3D)
      l.cov_LinW_m2.topLeftCorner<2, 2>() += extra_sigma_m * extra_sigma_m * Eigen::Matrix2d::Identity();
  return map;
}

/// Every landmark of A (the fused ones replaced), then B's unmatched ones moved into W_A, new ids.
void assemble(const std::vector<slam::Landmark>& A, const std::vector<slam::Landmark>& B, const Pairs& pairs,
              const std::vector<Eigen::Vector3d>& p, const std::vector<Eigen::Matrix3d>& cov_p, MergedMap& m) {
  std::uint64_t next_id = 0;
  for (const slam::Landmark& l : A) next_id = std::max(next_id, l.id + 1);
  for (std::size_t i = 0; i < A.size(); ++i) {
    slam::Landmark l = A[i];
    const int k = pairs.k_of_a[i];
    if (k >= 0) {
      const std::size_t u = static_cast<std::size_t>(k);
      l.p_LinW_m = p[u], l.cov_LinW_m2 = cov_p[u], ++m.fused;
      l.counter += B[static_cast<std::size_t>(pairs.b_of_k[u])].counter;
    } else {
      ++m.kept_A;
    }
    m.landmarks.push_back(l);
  }
  const Eigen::Matrix3d R = rotation3(m.T_AB);
  for (std::size_t j = 0; j < B.size(); ++j) {
    if (pairs.matched_b[j]) continue;
    slam::Landmark l = B[j];
    const Eigen::Matrix3d J = movedLampJacobian(m.T_AB, l.p_LinW_m);
    l.id = next_id++;
    l.p_LinW_m = slam::transformLamp(m.T_AB, l.p_LinW_m);
    l.cov_LinW_m2 = R * l.cov_LinW_m2 * R.transpose() + J * m.cov_T * J.transpose();
    m.landmarks.push_back(l);
    ++m.moved_B;
  }
}

}  // namespace

MergedMap mergeMaps(const std::vector<slam::Landmark>& given_A, const std::vector<slam::Landmark>& given_B,
                    const slam::RegisteredTransform& registration, double extra_sigma_m,
                    const MergeTransform& transform) {
  if (!(extra_sigma_m >= 0.0 && std::isfinite(extra_sigma_m)))
    throw std::invalid_argument("mergeMaps: extra_sigma_m must be finite and >= 0");
  const std::vector<slam::Landmark> A = inflated(given_A, extra_sigma_m), B = inflated(given_B, extra_sigma_m);
  const Pairs pairs = checkedPairs(A, B, registration.inliers);
  const auto* fixed = std::get_if<FixedTransform>(&transform);
  MergedMap m;
  m.T_AB = fixed ? fixed->T_AB : registration.T_AB;
  m.cov_T = fixed ? Eigen::Matrix3d::Zero() : registration.cov;
  const auto& in = registration.inliers;
  std::vector<Eigen::Vector3d> p(in.size());
  std::vector<Eigen::Matrix3d> cov_p(in.size());
  for (std::size_t k = 0; k < in.size(); ++k)  // the start, and the result when the solve fails
    informationFusion(A[static_cast<std::size_t>(in[k].first)], B[static_cast<std::size_t>(in[k].second)], m.T_AB, p[k],
                      cov_p[k]);
  double T[3] = {m.T_AB.x_m, m.T_AB.y_m, m.T_AB.theta_rad};
  std::vector<Eigen::Vector3d> p_solved = p;
  std::vector<Eigen::Matrix3d> cov_solved = cov_p;
  Eigen::Matrix3d cov_T = m.cov_T;
  std::string why;
  m.solved = !in.empty() && jointSolve(A, B, in, fixed != nullptr, T, p_solved, cov_T, cov_solved, why);
  if (m.solved) {
    m.T_AB = Pose2{T[0], T[1], wrapAngle(T[2])}, m.cov_T = cov_T, p = p_solved, cov_p = cov_solved;
    m.message = "joint solve of T_AB and " + std::to_string(in.size()) + " fused lamps converged";
  } else {
    m.message = (in.empty() ? std::string("no matched lamps") : why) +
                ": the registration's T_AB and the information-weighted means kept";
  }
  assemble(given_A, given_B, pairs, p, cov_p, m);  // unmatched lamps keep their own covariances
  return m;
}

}  // namespace omnislam::smoothing
