// Camera mounting extrinsic: where the optical centre sits in the robot frame R and how the camera
// axes are rotated (yaw, pitch, roll), with the direction/point transforms between C and R
// (docs/user/conventions.md, docs/design/camera-models.md "Mounting").
//
// C is R translated to p_CinR = (x_m, y_m, z_m) and rotated by R_CtoR = Rz(yaw) Ry(pitch) Rx(roll)
// (intrinsic z-y'-x'' angles: yaw about z_R, then pitch about the new y, then roll about the new x):
//   d_R = R_CtoR d_C,   p_C = R_CtoR^T (p_R - p_CinR).
// Level mounting (roll = pitch = 0, the simulated cameras): z_C parallel to z_R (both up), the
// elevation is the same in C and R and azimuth_R = azimuth_C + yaw_rad (wrapped); that path keeps the
// yaw-only arithmetic exactly, so level results are bit-identical to the yaw-only mounting.
// Example, a forward-looking camera (optical axis z_C along x_R, image up = -y_C along z_R):
//   roll = -pi/2, pitch = 0, yaw = -pi/2  ->  R_CtoR = [0 0 1; -1 0 0; 0 -1 0].
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "omnislam/core/angles.h"

namespace omnislam::camera {

struct CameraMounting {
  double x_m = 0.0;        ///< optical centre, forward of the robot origin [m]
  double y_m = 0.0;        ///< optical centre, left of the robot origin [m]
  double z_m = 1.8;        ///< optical centre above the floor [m] (paper 000's camera: 1.8 m)
  double yaw_rad = 0.0;    ///< rotation about z_R (from x_R towards y_R), applied first [rad]
  double roll_rad = 0.0;   ///< rotation about the camera's x axis, applied last [rad]; 0 = level
  double pitch_rad = 0.0;  ///< rotation about the yawed y axis [rad]; 0 = level
};

/// True when z_C is parallel to z_R (roll = pitch = 0): the yaw-only formulas apply.
inline bool isLevel(const CameraMounting& m) { return m.roll_rad == 0.0 && m.pitch_rad == 0.0; }

/// R_CtoR (3x3) = Rz(yaw) Ry(pitch) Rx(roll): rotation taking camera-axis components to robot-axis
/// components. For a level mounting, exactly the yaw-only matrix.
inline Eigen::Matrix3d rotationCameraToRobot(const CameraMounting& m) {
  const double c = std::cos(m.yaw_rad), s = std::sin(m.yaw_rad);
  Eigen::Matrix3d R;
  R << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
  if (isLevel(m)) return R;
  const double cp = std::cos(m.pitch_rad), sp = std::sin(m.pitch_rad);
  const double cr = std::cos(m.roll_rad), sr = std::sin(m.roll_rad);
  Eigen::Matrix3d Ry, Rx;
  Ry << cp, 0.0, sp, 0.0, 1.0, 0.0, -sp, 0.0, cp;
  Rx << 1.0, 0.0, 0.0, 0.0, cr, -sr, 0.0, sr, cr;
  return R * Ry * Rx;
}

/// p_CinR [m]: the optical centre in R.
inline Eigen::Vector3d cameraPositionInRobot_m(const CameraMounting& m) { return {m.x_m, m.y_m, m.z_m}; }

/// d_R = R_CtoR d_C. J_dR_dC (3x3) = R_CtoR; J_dR_yaw (3x1) = d(d_R)/d(yaw) = [e_z]x R_CtoR d_C (yaw is
/// the outermost rotation, so this holds for any roll and pitch).
inline Eigen::Vector3d directionCameraToRobot(const CameraMounting& m, const Eigen::Vector3d& d_C,
                                              Eigen::Matrix3d* J_dR_dC = nullptr, Eigen::Vector3d* J_dR_yaw = nullptr) {
  const Eigen::Matrix3d R = rotationCameraToRobot(m);
  const Eigen::Vector3d d_R = R * d_C;
  if (J_dR_dC) *J_dR_dC = R;
  if (J_dR_yaw) *J_dR_yaw = Eigen::Vector3d(-d_R.y(), d_R.x(), 0.0);  // dRz/dyaw = [e_z]x Rz
  return d_R;
}

/// d_C = R_CtoR^T d_R. J_dC_dR (3x3) = R_CtoR^T.
inline Eigen::Vector3d directionRobotToCamera(const CameraMounting& m, const Eigen::Vector3d& d_R,
                                              Eigen::Matrix3d* J_dC_dR = nullptr) {
  const Eigen::Matrix3d Rt = rotationCameraToRobot(m).transpose();
  if (J_dC_dR) *J_dC_dR = Rt;
  return Rt * d_R;
}

/// p_C = R_CtoR^T (p_R - p_CinR) [m]: a point given in R, seen from the optical centre in C axes.
/// J_pC_pR (3x3) = R_CtoR^T.
inline Eigen::Vector3d pointRobotToCamera(const CameraMounting& m, const Eigen::Vector3d& p_R_m,
                                          Eigen::Matrix3d* J_pC_pR = nullptr) {
  const Eigen::Matrix3d Rt = rotationCameraToRobot(m).transpose();
  if (J_pC_pR) *J_pC_pR = Rt;
  return Rt * (p_R_m - cameraPositionInRobot_m(m));
}

/// Bearing in C -> bearing in R axes. Level mounting: azimuth + yaw (wrapped to (-pi, pi]),
/// elevation unchanged. Otherwise the azimuth and elevation of R_CtoR unitOf(b_C).
inline Bearing bearingCameraToRobot(const CameraMounting& m, const Bearing& b_C) {
  if (isLevel(m)) return {wrapAngle(b_C.azimuth_rad + m.yaw_rad), b_C.elevation_rad};
  return bearingOf(rotationCameraToRobot(m) * unitOf(b_C));
}

}  // namespace omnislam::camera
