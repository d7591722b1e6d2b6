// Measurement model h of paper 000 (Sec. III-A, Alg. 2 lines 2-4): bearing of a world landmark
// seen from a camera mounted on a planar robot, with Jacobians w.r.t. the pose and the landmark.
//
// Camera centre in W:  p_CinW = (x, y, 0) + Rz(theta) p_CinR
// Direction in R axes: d = Rz(theta)^T (p_LinW - p_CinW)
// Point (kPoint3D):          z = (azimuth, elevation) = (atan2(d_y, d_x), atan2(d_z, hypot(d_x, d_y)))
// Vertical line (kVerticalLine, landmark (x, y), z unused):  z = azimuth only (first row above).
// Pose Jacobians are w.r.t. (x_m, y_m, theta_rad) of R in W; landmark Jacobians w.r.t. p_LinW_m.
#pragma once

#include <Eigen/Core>
#include <optional>

#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::slam {

/// Below this horizontal distance between the camera and the landmark [m] the azimuth is undefined
/// (landmark at the zenith/nadir or at the optical centre): the model returns std::nullopt.
constexpr double kMinHorizontalRange_m = 1e-6;

/// Measurement vectors of either kind: dimension 2 (point) or 1 (vertical line), no heap.
using MeasVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 2, 1>;
using MeasMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 2, 2>;
using MeasJac = Eigen::Matrix<double, Eigen::Dynamic, 3, 0, 2, 3>;  ///< dim x 3

/// Optical centre in W [m] for the robot pose T_WtoR and the mounting p_CinR_m.
Eigen::Vector3d cameraCentreInWorld(const Pose2& T_WtoR, const Eigen::Vector3d& p_CinR_m);

/// Unit direction in W of a bearing given in robot-parallel axes at heading theta_rad.
Eigen::Vector3d bearingDirectionInWorld(double azimuth_rad, double elevation_rad, double theta_rad);

/// Point model: (azimuth, elevation) [rad] of p_LinW_m; std::nullopt when the horizontal range is
/// below kMinHorizontalRange_m. J_z_pose (2x3, d z / d (x, y, theta)) and J_z_landmark
/// (2x3, d z / d p_LinW) are filled when non-null.
std::optional<Eigen::Vector2d> predictBearing(const Eigen::Vector3d& p_LinW_m, const Pose2& T_WtoR,
                                              const Eigen::Vector3d& p_CinR_m,
                                              Eigen::Matrix<double, 2, 3>* J_z_pose = nullptr,
                                              Eigen::Matrix<double, 2, 3>* J_z_landmark = nullptr);

/// Measurement dimension of a landmark kind: 2 for kPoint3D, 1 for kVerticalLine.
int measurementDim(LandmarkKind kind);

/// Model chosen by landmark kind (the filter calls only this): prediction of dimension
/// measurementDim(kind) and Jacobians (dim x 3) when non-null; std::nullopt when undefined.
std::optional<MeasVec> predictMeasurement(LandmarkKind kind, const Eigen::Vector3d& p_LinW_m, const Pose2& T_WtoR,
                                          const Eigen::Vector3d& p_CinR_m, MeasJac* J_z_pose = nullptr,
                                          MeasJac* J_z_landmark = nullptr);
/// The same with cos and sin of T_WtoR.theta_rad given: a caller predicting many points from one
/// pose computes them once. Equal to the overload above, bit for bit, when they are std::cos and
/// std::sin of it.
std::optional<MeasVec> predictMeasurement(LandmarkKind kind, const Eigen::Vector3d& p_LinW_m, const Pose2& T_WtoR,
                                          double cos_theta, double sin_theta, const Eigen::Vector3d& p_CinR_m,
                                          MeasJac* J_z_pose = nullptr, MeasJac* J_z_landmark = nullptr);

/// The measured vector z of a measurement (its kind decides the dimension).
MeasVec measurementVector(const BearingMeasurement& m);

/// Q_t of a measurement, dimension of its kind. With inflate_azimuth_near_zenith the azimuth
/// variance is raised to at least var(elevation) / cos^2(elevation) (capped at pi^2): an isotropic
/// angular error on the sphere, which is what pixel noise near the optical axis of an upward
/// fish-eye produces, and which keeps the azimuth linearisation honest near the zenith.
MeasMat measurementCovariance(const BearingMeasurement& m, bool inflate_azimuth_near_zenith);

/// z - zhat with every component wrapped to (-pi, pi] (angle differences, docs/user/conventions.md).
MeasVec innovation(const MeasVec& z, const MeasVec& zhat);

/// log N(r; 0, S) = -(dim log(2 pi) + log|S| + r^T S^-1 r) / 2; -infinity if S is not positive
/// definite. When mahalanobis_sq is non-null it receives r^T S^-1 r (+infinity if S is not PD).
double logGaussian(const MeasVec& r, const MeasMat& S, double* mahalanobis_sq = nullptr);

}  // namespace omnislam::slam
