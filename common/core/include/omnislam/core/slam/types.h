// Plain data types shared by the FastSLAM core: landmark kinds and types, bearing measurements,
// landmarks. Frames and units follow docs/user/conventions.md (W world, R robot, C camera; SI units).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>

namespace omnislam::slam {

/// What a landmark physically is; it selects the measurement model (see bearing_model.h).
enum class LandmarkKind : std::uint8_t {
  kPoint3D = 0,       ///< a point, e.g. a ceiling light: measured by (azimuth, elevation)
  kVerticalLine = 1,  ///< an infinite vertical line at (x, y): measured by azimuth only
};

/// Paper 000, Sec. III-F 2: type I landmarks correct the pose (Alg. 3) and weigh the particle
/// (Alg. 4); type II (initialised from far away, > D_min) are only updated.
enum class LandmarkType : std::uint8_t { kTypeI = 1, kTypeII = 2 };

/// Appearance of a feature or landmark: for a vertical line the mean colours (R, G, B, 0..255) on
/// its counter-clockwise and clockwise sides (paper 002's neighbourhood colour). Optional.
struct ColourDescriptor {
  bool valid = false;
  std::array<float, 6> rgb{};  ///< colour_a (R, G, B), colour_b (R, G, B)
  /// Euclidean distance in RGB units over the six values (both must be valid).
  double distanceTo(const ColourDescriptor& o) const {
    double s = 0.0;
    for (std::size_t i = 0; i < 6; ++i) s += (double(rgb[i]) - double(o.rgb[i])) * (double(rgb[i]) - double(o.rgb[i]));
    return std::sqrt(s);
  }
};

/// One detected feature. The bearing is expressed in axes parallel to the robot frame R with its
/// origin at the camera's optical centre, whose position in R is p_CinR_m (docs/user/conventions.md).
struct BearingMeasurement {
  double azimuth_rad = 0.0;    ///< counter-clockwise from +x_R, (-pi, pi]
  double elevation_rad = 0.0;  ///< above the x_R-y_R plane, [-pi/2, pi/2]; unused for kVerticalLine
  /// Covariance of (azimuth, elevation) [rad^2]; for kVerticalLine only entry (0, 0) is used.
  Eigen::Matrix2d cov_rad2 = Eigen::Matrix2d::Identity() * 2.7e-5;  // (0.3 deg)^2
  Eigen::Vector3d p_CinR_m = Eigen::Vector3d::Zero();               ///< optical centre in the robot frame [m]
  LandmarkKind kind = LandmarkKind::kPoint3D;
  ColourDescriptor descriptor;  ///< optional appearance (FastSlamOptions::descriptor_gate)
};

/// A map landmark of one particle (paper 000: B_j = mean, covariance, detection counter i_j, type).
/// For kVerticalLine, p_LinW_m.z() is not observed (its Jacobian column is zero) and is kept as is.
struct Landmark {
  std::uint64_t id = 0;  ///< unique in the filter, stable, inherited through resampling
  Eigen::Vector3d p_LinW_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov_LinW_m2 = Eigen::Matrix3d::Identity();
  int counter = 1;  ///< i_j: +1 when detected, -1 when missed inside the perceptual range
  LandmarkType type = LandmarkType::kTypeI;
  LandmarkKind kind = LandmarkKind::kPoint3D;
  ColourDescriptor descriptor;  ///< running mean of the associated measurements' descriptors
};

}  // namespace omnislam::slam
