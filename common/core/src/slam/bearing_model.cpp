// Bearing measurement model h and its Jacobians (paper 000, Sec. III-A; equations in the header).
#include "omnislam/core/slam/bearing_model.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>

namespace omnislam::slam {

Eigen::Vector3d cameraCentreInWorld(const Pose2& T_WtoR, const Eigen::Vector3d& p_CinR_m) {
  const double c = std::cos(T_WtoR.theta_rad), s = std::sin(T_WtoR.theta_rad);
  return {T_WtoR.x_m + c * p_CinR_m.x() - s * p_CinR_m.y(), T_WtoR.y_m + s * p_CinR_m.x() + c * p_CinR_m.y(),
          p_CinR_m.z()};
}

Eigen::Vector3d bearingDirectionInWorld(double azimuth_rad, double elevation_rad, double theta_rad) {
  return unitOf(Bearing{azimuth_rad + theta_rad, elevation_rad});
}

namespace {

// The point model with the heading's cosine and sine given. with_elevation false leaves z(1) at 0
// and does not compute it (a vertical line has no elevation; one atan2 less per prediction).
std::optional<Eigen::Vector2d> predictBearingCS(const Eigen::Vector3d& p_LinW_m, const Pose2& T_WtoR, double c,
                                                double s, const Eigen::Vector3d& p_CinR_m, bool with_elevation,
                                                Eigen::Matrix<double, 2, 3>* J_z_pose,
                                                Eigen::Matrix<double, 2, 3>* J_z_landmark) {
  // d' = Rz^T (p_LinW - t): landmark in R; d = d' - p_CinR: direction from the optical centre.
  const double ex = p_LinW_m.x() - T_WtoR.x_m, ey = p_LinW_m.y() - T_WtoR.y_m;
  const double dpx = c * ex + s * ey, dpy = -s * ex + c * ey;
  const Eigen::Vector3d d(dpx - p_CinR_m.x(), dpy - p_CinR_m.y(), p_LinW_m.z() - p_CinR_m.z());
  const double rho2 = d.x() * d.x() + d.y() * d.y();
  const double rho = std::sqrt(rho2);
  if (!(rho >= kMinHorizontalRange_m)) return std::nullopt;
  const Eigen::Vector2d z(std::atan2(d.y(), d.x()), with_elevation ? std::atan2(d.z(), rho) : 0.0);
  if (J_z_pose == nullptr && J_z_landmark == nullptr) return z;

  const double r2 = rho2 + d.z() * d.z();
  Eigen::Matrix<double, 2, 3> J_z_d;          // d z / d d
  J_z_d << -d.y() / rho2, d.x() / rho2, 0.0,  //
      -d.z() * d.x() / (rho * r2), -d.z() * d.y() / (rho * r2), rho / r2;
  Eigen::Matrix3d RzT;  // d d / d p_LinW
  RzT << c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0;
  if (J_z_landmark != nullptr) *J_z_landmark = J_z_d * RzT;  // 2x3 * 3x3
  if (J_z_pose != nullptr) {
    Eigen::Matrix3d J_d_pose;  // columns: d/dx, d/dy, d/dtheta
    J_d_pose.col(0) = -RzT.col(0);
    J_d_pose.col(1) = -RzT.col(1);
    J_d_pose.col(2) << dpy, -dpx, 0.0;
    *J_z_pose = J_z_d * J_d_pose;  // 2x3 * 3x3
  }
  return z;
}

}  // namespace

std::optional<Eigen::Vector2d> predictBearing(const Eigen::Vector3d& p_LinW_m, const Pose2& T_WtoR,
                                              const Eigen::Vector3d& p_CinR_m, Eigen::Matrix<double, 2, 3>* J_z_pose,
                                              Eigen::Matrix<double, 2, 3>* J_z_landmark) {
  return predictBearingCS(p_LinW_m, T_WtoR, std::cos(T_WtoR.theta_rad), std::sin(T_WtoR.theta_rad), p_CinR_m, true,
                          J_z_pose, J_z_landmark);
}

int measurementDim(LandmarkKind kind) { return kind == LandmarkKind::kVerticalLine ? 1 : 2; }

std::optional<MeasVec> predictMeasurement(LandmarkKind kind, const Eigen::Vector3d& p_LinW_m, const Pose2& T_WtoR,
                                          double cos_theta, double sin_theta, const Eigen::Vector3d& p_CinR_m,
                                          MeasJac* J_z_pose, MeasJac* J_z_landmark) {
  Eigen::Matrix<double, 2, 3> Jp, Jl;
  const int dim = measurementDim(kind);
  const auto z = predictBearingCS(p_LinW_m, T_WtoR, cos_theta, sin_theta, p_CinR_m, dim == 2, J_z_pose ? &Jp : nullptr,
                                  J_z_landmark ? &Jl : nullptr);
  if (!z) return std::nullopt;
  MeasVec out = z->head(dim);
  if (J_z_pose) *J_z_pose = Jp.topRows(dim);
  if (J_z_landmark) *J_z_landmark = Jl.topRows(dim);  // azimuth row: zero column for z already
  return out;
}

std::optional<MeasVec> predictMeasurement(LandmarkKind kind, const Eigen::Vector3d& p_LinW_m, const Pose2& T_WtoR,
                                          const Eigen::Vector3d& p_CinR_m, MeasJac* J_z_pose, MeasJac* J_z_landmark) {
  return predictMeasurement(kind, p_LinW_m, T_WtoR, std::cos(T_WtoR.theta_rad), std::sin(T_WtoR.theta_rad), p_CinR_m,
                            J_z_pose, J_z_landmark);
}

MeasVec measurementVector(const BearingMeasurement& m) {
  const int dim = measurementDim(m.kind);
  MeasVec z(dim);
  z(0) = m.azimuth_rad;
  if (dim == 2) z(1) = m.elevation_rad;
  return z;
}

MeasMat measurementCovariance(const BearingMeasurement& m, bool inflate_azimuth_near_zenith) {
  const int dim = measurementDim(m.kind);
  MeasMat Q = m.cov_rad2.topLeftCorner(dim, dim);
  if (dim == 2 && inflate_azimuth_near_zenith) {
    const double ce = std::cos(m.elevation_rad);
    const double floor_var = ce * ce * kPi * kPi > m.cov_rad2(1, 1) ? m.cov_rad2(1, 1) / (ce * ce) : kPi * kPi;
    if (Q(0, 0) < floor_var) {
      // Keep the correlation coefficient while raising the azimuth variance.
      const double scale = Q(0, 0) > 0.0 ? std::sqrt(floor_var / Q(0, 0)) : 0.0;
      Q(0, 1) *= scale;
      Q(1, 0) *= scale;
      Q(0, 0) = floor_var;
    }
  }
  return Q;
}

MeasVec innovation(const MeasVec& z, const MeasVec& zhat) {
  MeasVec r(z.size());
  for (Eigen::Index i = 0; i < z.size(); ++i) r(i) = wrapAngle(z(i) - zhat(i));
  return r;
}

double logGaussian(const MeasVec& r, const MeasMat& S, double* mahalanobis_sq) {
  if (S.rows() == 1 && S.cols() == 1 && r.size() == 1) {
    // The general path below for one dimension, written out: the same operations in the same order
    // as Eigen's LLT and triangular solve (so the same bits, tested), without their set-up, which
    // dominates at this size (azimuth-only measurements are scored once per candidate and particle).
    const double s00 = S(0, 0);
    if (s00 <= 0.0) {  // LLT's test: a NaN passes it, as there
      if (mahalanobis_sq) *mahalanobis_sq = std::numeric_limits<double>::infinity();
      return -std::numeric_limits<double>::infinity();
    }
    const double l00 = std::sqrt(s00);
    const double y = r(0) != 0.0 ? r(0) / l00 : r(0);  // the solve skips a zero right-hand side
    const double m2 = y * y;
    const double log_det = 0.0 + 2.0 * std::log(l00);
    if (mahalanobis_sq) *mahalanobis_sq = m2;
    return -0.5 * (1.0 * std::log(2.0 * kPi) + log_det + m2);
  }
  if (S.rows() == 2 && S.cols() == 2 && r.size() == 2) {
    // The same for two dimensions: Eigen's unblocked LLT of the lower triangle (its test: a NaN
    // passes), its forward substitution (skipping a zero right-hand side), in the same order; the
    // generic path's set-up was most of its cost (twice per associated pair and particle).
    const double a00 = S(0, 0);
    const double l00 = std::sqrt(a00);
    const double l10 = S(1, 0) / l00;
    const double x11 = S(1, 1) - l10 * l10;
    if (a00 <= 0.0 || x11 <= 0.0) {
      if (mahalanobis_sq) *mahalanobis_sq = std::numeric_limits<double>::infinity();
      return -std::numeric_limits<double>::infinity();
    }
    const double l11 = std::sqrt(x11);
    double y0 = r(0), y1 = r(1);
    if (y0 != 0.0) {
      y0 /= l00;
      y1 -= y0 * l10;
    }
    if (y1 != 0.0) y1 /= l11;
    const double m2 = y0 * y0 + y1 * y1;
    double log_det = 0.0;
    log_det += 2.0 * std::log(l00);
    log_det += 2.0 * std::log(l11);
    if (mahalanobis_sq) *mahalanobis_sq = m2;
    return -0.5 * (2.0 * std::log(2.0 * kPi) + log_det + m2);
  }
  const Eigen::LLT<MeasMat> llt(S);
  if (llt.info() != Eigen::Success) {
    if (mahalanobis_sq) *mahalanobis_sq = std::numeric_limits<double>::infinity();
    return -std::numeric_limits<double>::infinity();
  }
  const MeasVec y = llt.matrixL().solve(r);
  const double m2 = y.squaredNorm();
  double log_det = 0.0;
  for (Eigen::Index i = 0; i < S.rows(); ++i) log_det += 2.0 * std::log(llt.matrixL()(i, i));
  if (mahalanobis_sq) *mahalanobis_sq = m2;
  return -0.5 * (static_cast<double>(r.size()) * std::log(2.0 * kPi) + log_det + m2);
}

}  // namespace omnislam::slam
