// Residuals, analytic Jacobians and Ceres cost functions of the keyframe graph (factors.h).
#include "omnislam/smoothing/factors.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>

#include "omnislam/core/angles.h"
#include "omnislam/core/slam/bearing_model.h"

namespace omnislam::smoothing {
namespace {

Pose2 poseOf(const double* p) { return {p[0], p[1], p[2]}; }

/// Copies a row-major Jacobian block for Ceres (each block is N x size, row-major).
template <int N, int M>
void writeJacobian(double* out, const Eigen::Matrix<double, N, M>& J) {
  Eigen::Map<Eigen::Matrix<double, N, M, Eigen::RowMajor>> map(out);
  map = J;
}

}  // namespace

template <int N>
std::optional<Eigen::Matrix<double, N, N>> whitener(const Eigen::Matrix<double, N, N>& Sigma) {
  if (!Sigma.allFinite()) return std::nullopt;
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt(Sigma);
  if (llt.info() != Eigen::Success) return std::nullopt;
  const Eigen::Matrix<double, N, N> L = llt.matrixL();
  if ((L.diagonal().array() <= 0.0).any()) return std::nullopt;
  return L.template triangularView<Eigen::Lower>().solve(Eigen::Matrix<double, N, N>::Identity());
}
template std::optional<Eigen::Matrix<double, 2, 2>> whitener<2>(const Eigen::Matrix<double, 2, 2>&);
template std::optional<Eigen::Matrix<double, 3, 3>> whitener<3>(const Eigen::Matrix<double, 3, 3>&);

Eigen::Vector3d posePriorError(const Pose2& T_WtoR, const Pose2& prior, Matrix3d* J_e_pose) {
  if (J_e_pose) J_e_pose->setIdentity();
  return {T_WtoR.x_m - prior.x_m, T_WtoR.y_m - prior.y_m, wrapAngle(T_WtoR.theta_rad - prior.theta_rad)};
}

Eigen::Vector3d odometryError(const Pose2& a, const Pose2& b, const Pose2& u, Matrix3d* J_e_a, Matrix3d* J_e_b) {
  const double c = std::cos(a.theta_rad), s = std::sin(a.theta_rad);
  const double dx = b.x_m - a.x_m, dy = b.y_m - a.y_m;
  const Eigen::Vector3d e(c * dx + s * dy - u.x_m, -s * dx + c * dy - u.y_m,
                          wrapAngle(b.theta_rad - a.theta_rad - u.theta_rad));
  if (J_e_a) *J_e_a << -c, -s, -s * dx + c * dy, s, -c, -c * dx - s * dy, 0.0, 0.0, -1.0;
  if (J_e_b) *J_e_b << c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0;
  return e;
}

Pose2 calibratedIncrement(const Pose2& u, double scale, double drift, Eigen::Matrix<double, 3, 2>* J_u_c) {
  const double d = std::hypot(u.x_m, u.y_m), phi = 0.5 * drift * d;
  const double c = std::cos(phi), s = std::sin(phi);
  const Eigen::Vector2d r(c * u.x_m - s * u.y_m, s * u.x_m + c * u.y_m);  // R(phi) u_xy
  if (J_u_c) {
    const Eigen::Vector2d dr(-s * u.x_m - c * u.y_m, c * u.x_m - s * u.y_m);  // d R(phi) u_xy / d phi
    J_u_c->col(0) << r, 0.0;
    J_u_c->col(1) << scale * 0.5 * d * dr, d;
  }
  return {scale * r.x(), scale * r.y(), u.theta_rad + drift * d};
}

std::optional<Eigen::Vector2d> pointBearingError(const slam::BearingMeasurement& z, const Pose2& T_WtoR,
                                                 const Eigen::Vector3d& p_LinW_m, Eigen::Matrix<double, 2, 3>* J_e_pose,
                                                 Eigen::Matrix<double, 2, 3>* J_e_landmark) {
  const auto zhat = slam::predictBearing(p_LinW_m, T_WtoR, z.p_CinR_m, J_e_pose, J_e_landmark);
  if (!zhat) return std::nullopt;
  // e = z - h: the Jacobians of e are minus those of h.
  if (J_e_pose) *J_e_pose = -*J_e_pose;
  if (J_e_landmark) *J_e_landmark = -*J_e_landmark;
  return Eigen::Vector2d(wrapAngle(z.azimuth_rad - zhat->x()), wrapAngle(z.elevation_rad - zhat->y()));
}

std::optional<double> lineAzimuthError(const slam::BearingMeasurement& z, const Pose2& T_WtoR,
                                       const Eigen::Vector2d& p_LinW_xy_m, Eigen::Matrix<double, 1, 3>* J_e_pose,
                                       Eigen::Matrix<double, 1, 2>* J_e_landmark) {
  slam::MeasJac Jp, Jl;
  const Eigen::Vector3d p(p_LinW_xy_m.x(), p_LinW_xy_m.y(), 0.0);
  const auto zhat = slam::predictMeasurement(slam::LandmarkKind::kVerticalLine, p, T_WtoR, z.p_CinR_m,
                                             J_e_pose ? &Jp : nullptr, J_e_landmark ? &Jl : nullptr);
  if (!zhat) return std::nullopt;
  if (J_e_pose) *J_e_pose = -Jp.row(0);
  if (J_e_landmark) *J_e_landmark = -Jl.row(0).head<2>();
  return wrapAngle(z.azimuth_rad - (*zhat)(0));
}

// --- Cost functions ---------------------------------------------------------------------------

PosePriorCost::PosePriorCost(const Pose2& prior, const Matrix3d& Sigma)
    : prior_(prior), W_(whitener<3>(Sigma).value_or(Matrix3d::Zero())) {}

bool PosePriorCost::Evaluate(double const* const* params, double* residuals, double** jacobians) const {
  Eigen::Map<Eigen::Vector3d>{residuals} = W_ * posePriorError(poseOf(params[0]), prior_);
  if (jacobians && jacobians[0]) writeJacobian<3, 3>(jacobians[0], W_);
  return true;
}

OdometryCost::OdometryCost(const Pose2& u_AtoB, const Matrix3d& Sigma_u)
    : u_(u_AtoB), W_(whitener<3>(Sigma_u).value_or(Matrix3d::Zero())) {}

bool OdometryCost::Evaluate(double const* const* params, double* residuals, double** jacobians) const {
  Matrix3d Ja, Jb;
  const bool want = jacobians != nullptr;
  const Eigen::Vector3d e =
      odometryError(poseOf(params[0]), poseOf(params[1]), u_, want ? &Ja : nullptr, want ? &Jb : nullptr);
  Eigen::Map<Eigen::Vector3d>{residuals} = W_ * e;
  if (want && jacobians[0]) writeJacobian<3, 3>(jacobians[0], W_ * Ja);
  if (want && jacobians[1]) writeJacobian<3, 3>(jacobians[1], W_ * Jb);
  return true;
}

CalibratedOdometryCost::CalibratedOdometryCost(const Pose2& u_AtoB, const Matrix3d& Sigma_u)
    : u_(u_AtoB), W_(whitener<3>(Sigma_u).value_or(Matrix3d::Zero())) {}

bool CalibratedOdometryCost::Evaluate(double const* const* params, double* residuals, double** jacobians) const {
  Matrix3d Ja, Jb;
  Eigen::Matrix<double, 3, 2> Ju;
  const bool want = jacobians != nullptr;
  const Pose2 u = calibratedIncrement(u_, params[2][0], params[2][1], want ? &Ju : nullptr);
  // The increment enters the error with a minus sign (odometryError: e = measured - u).
  Eigen::Vector3d e = odometryError(poseOf(params[0]), poseOf(params[1]), Pose2{u.x_m, u.y_m, 0.0},
                                    want ? &Ja : nullptr, want ? &Jb : nullptr);
  e(2) = wrapAngle(params[1][2] - params[0][2] - u.theta_rad);
  Eigen::Map<Eigen::Vector3d>{residuals} = W_ * e;
  if (want && jacobians[0]) writeJacobian<3, 3>(jacobians[0], W_ * Ja);
  if (want && jacobians[1]) writeJacobian<3, 3>(jacobians[1], W_ * Jb);
  if (want && jacobians[2]) writeJacobian<3, 2>(jacobians[2], Eigen::Matrix<double, 3, 2>(-W_ * Ju));
  return true;
}

CalibrationPriorCost::CalibrationPriorCost(double scale_sigma, double drift_sigma)
    : inv_s_(1.0 / scale_sigma), inv_d_(1.0 / drift_sigma) {}

bool CalibrationPriorCost::Evaluate(double const* const* params, double* residuals, double** jacobians) const {
  residuals[0] = inv_s_ * (params[0][0] - 1.0);
  residuals[1] = inv_d_ * params[0][1];
  if (jacobians && jacobians[0]) {
    jacobians[0][0] = inv_s_;
    jacobians[0][1] = 0.0;
    jacobians[0][2] = 0.0;
    jacobians[0][3] = inv_d_;
  }
  return true;
}

PointBearingCost::PointBearingCost(const slam::BearingMeasurement& z, const Eigen::Matrix2d& Sigma)
    : z_(z), W_(whitener<2>(Sigma).value_or(Eigen::Matrix2d::Zero())) {}

bool PointBearingCost::Evaluate(double const* const* params, double* residuals, double** jacobians) const {
  Eigen::Matrix<double, 2, 3> Jp, Jl;
  const bool want = jacobians != nullptr;
  const auto e = pointBearingError(z_, poseOf(params[0]), Eigen::Vector3d(params[1][0], params[1][1], params[1][2]),
                                   want ? &Jp : nullptr, want ? &Jl : nullptr);
  if (!e) return false;  // undefined here: Ceres rejects the step
  Eigen::Map<Eigen::Vector2d>{residuals} = W_ * *e;
  if (want && jacobians[0]) writeJacobian<2, 3>(jacobians[0], W_ * Jp);
  if (want && jacobians[1]) writeJacobian<2, 3>(jacobians[1], W_ * Jl);
  return true;
}

LineAzimuthCost::LineAzimuthCost(const slam::BearingMeasurement& z, double sigma_rad)
    : z_(z), inv_sigma_(1.0 / sigma_rad) {}

bool LineAzimuthCost::Evaluate(double const* const* params, double* residuals, double** jacobians) const {
  Eigen::Matrix<double, 1, 3> Jp;
  Eigen::Matrix<double, 1, 2> Jl;
  const bool want = jacobians != nullptr;
  const auto e = lineAzimuthError(z_, poseOf(params[0]), Eigen::Vector2d(params[1][0], params[1][1]),
                                  want ? &Jp : nullptr, want ? &Jl : nullptr);
  if (!e) return false;
  residuals[0] = inv_sigma_ * *e;
  if (want && jacobians[0]) Eigen::Map<Eigen::Matrix<double, 1, 3>>{jacobians[0]} = inv_sigma_ * Jp;
  if (want && jacobians[1]) Eigen::Map<Eigen::Matrix<double, 1, 2>>{jacobians[1]} = inv_sigma_ * Jl;
  return true;
}

KnownHeightCost::KnownHeightCost(double height_m, double sigma_m) : height_m_(height_m), inv_sigma_(1.0 / sigma_m) {}

bool KnownHeightCost::Evaluate(double const* const* params, double* residuals, double** jacobians) const {
  residuals[0] = inv_sigma_ * (params[0][2] - height_m_);
  if (jacobians && jacobians[0]) {
    jacobians[0][0] = 0.0;
    jacobians[0][1] = 0.0;
    jacobians[0][2] = inv_sigma_;
  }
  return true;
}

FlatCeilingCost::FlatCeilingCost(double sigma_m) : inv_sigma_(1.0 / sigma_m) {}

bool FlatCeilingCost::Evaluate(double const* const* params, double* residuals, double** jacobians) const {
  residuals[0] = inv_sigma_ * (params[0][2] - params[1][0]);
  if (jacobians && jacobians[0]) {
    jacobians[0][0] = 0.0;
    jacobians[0][1] = 0.0;
    jacobians[0][2] = inv_sigma_;
  }
  if (jacobians && jacobians[1]) jacobians[1][0] = -inv_sigma_;
  return true;
}

template <int N>
LandmarkPriorCost<N>::LandmarkPriorCost(const Eigen::Matrix<double, N, 1>& mean_m,
                                        const Eigen::Matrix<double, N, N>& information)
    : mean_(mean_m) {
  // information = V diag(lambda) V^T: S = diag(sqrt(lambda)) V^T (negative round-off clamped to 0).
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es(information);
  S_ = es.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() * es.eigenvectors().transpose();
}

template <int N>
bool LandmarkPriorCost<N>::Evaluate(double const* const* params, double* residuals, double** jacobians) const {
  const Eigen::Map<const Eigen::Matrix<double, N, 1>> l(params[0]);
  Eigen::Map<Eigen::Matrix<double, N, 1>> r(residuals);
  r = S_ * (l - mean_);
  if (jacobians && jacobians[0]) {
    Eigen::Map<Eigen::Matrix<double, N, N, Eigen::RowMajor>> J(jacobians[0]);
    J = S_;
  }
  return true;
}

template class LandmarkPriorCost<2>;
template class LandmarkPriorCost<3>;

}  // namespace omnislam::smoothing
