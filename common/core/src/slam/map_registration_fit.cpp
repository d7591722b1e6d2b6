// The geometry of map registration (map_registration.h): a lamp moved by T_AB, the weighted
// least-squares T_AB of correspondences and its covariance, the decisions' names.
#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>

#include "omnislam/core/slam/map_registration.h"
#include "map_registration_detail.h"

namespace omnislam::slam {

const char* registrationDecisionName(RegistrationDecision d) {
  switch (d) {
    case RegistrationDecision::kAccepted: return "accepted";
    case RegistrationDecision::kInvalidInput: return "invalid input";
    case RegistrationDecision::kNoOverlap: return "no overlap";
    case RegistrationDecision::kChance: return "chance";
    case RegistrationDecision::kAmbiguous: return "ambiguous";
  }
  return "unknown";
}

Eigen::Vector3d transformLamp(const Pose2& T_AB, const Eigen::Vector3d& p_B) {
  const Eigen::Vector2d xy = T_AB.transformFrom(p_B.head<2>());
  return {xy.x(), xy.y(), p_B.z()};
}

namespace registration {

Eigen::Matrix<double, 2, 3> jacobianOfMovedPoint(const Pose2& T_AB, const Eigen::Vector2d& b) {
  const double c = std::cos(T_AB.theta_rad), s = std::sin(T_AB.theta_rad);
  Eigen::Matrix<double, 2, 3> J;
  J << 1.0, 0.0, -s * b.x() - c * b.y(), 0.0, 1.0, c * b.x() - s * b.y();
  return J;
}

Eigen::Matrix2d rotated(const Pose2& T_AB, const Eigen::Matrix2d& cov_B) {
  const double c = std::cos(T_AB.theta_rad), s = std::sin(T_AB.theta_rad);
  Eigen::Matrix2d R;
  R << c, -s, s, c;
  return R * cov_B * R.transpose();
}

bool transformInformation(const std::vector<Eigen::Vector2d>& b, const std::vector<Eigen::Matrix2d>& S,
                          const Pose2& T_AB, Eigen::Matrix3d& cov) {
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < b.size(); ++k) {
    const Eigen::Matrix<double, 2, 3> J = jacobianOfMovedPoint(T_AB, b[k]);
    H += J.transpose() * S[k].inverse() * J;
  }
  Eigen::FullPivLU<Eigen::Matrix3d> lu(H);
  if (!H.allFinite() || lu.rank() < 3) return false;
  cov = lu.inverse();
  cov = 0.5 * (cov + cov.transpose());
  return cov.allFinite();
}

}  // namespace registration

bool fitTransform(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b,
                  const std::vector<Eigen::Matrix2d>& S, Pose2& T_AB, Eigen::Matrix3d& cov) {
  if (a.size() != b.size() || a.size() != S.size() || a.size() < 2) return false;
  for (int it = 0; it < 20; ++it) {  // Gauss-Newton: e_k = a_k - T(b_k), minimise sum e^T S^-1 e
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < a.size(); ++k) {
      const Eigen::Matrix<double, 2, 3> J = registration::jacobianOfMovedPoint(T_AB, b[k]);
      const Eigen::Matrix2d W = S[k].inverse();
      H += J.transpose() * W * J;
      g += J.transpose() * W * (a[k] - T_AB.transformFrom(b[k]));
    }
    Eigen::FullPivLU<Eigen::Matrix3d> lu(H);
    if (!H.allFinite() || lu.rank() < 3) return false;
    const Eigen::Vector3d step = lu.solve(g);
    if (!step.allFinite()) return false;
    T_AB = Pose2{T_AB.x_m + step.x(), T_AB.y_m + step.y(), wrapAngle(T_AB.theta_rad + step.z())};
    if (step.head<2>().norm() < 1e-12 && std::abs(step.z()) < 1e-14) break;
  }
  return registration::transformInformation(b, S, T_AB, cov);
}

}  // namespace omnislam::slam
