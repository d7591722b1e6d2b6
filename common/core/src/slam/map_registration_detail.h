// Helpers shared by the files of map registration (map_registration.h); not part of the API.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "omnislam/core/pose2.h"

namespace omnislam::slam::registration {

/// d T_AB(b) / d (x_m, y_m, theta_rad), 2x3.
Eigen::Matrix<double, 2, 3> jacobianOfMovedPoint(const Pose2& T_AB, const Eigen::Vector2d& b);

/// R(theta) cov_B R(theta)^T: a covariance of B's frame in A's.
Eigen::Matrix2d rotated(const Pose2& T_AB, const Eigen::Matrix2d& cov_B);

/// cov = (sum J_k^T S_k^-1 J_k)^-1 of the points b_k at T_AB; false when singular.
bool transformInformation(const std::vector<Eigen::Vector2d>& b, const std::vector<Eigen::Matrix2d>& S,
                          const Pose2& T_AB, Eigen::Matrix3d& cov);

}  // namespace omnislam::slam::registration
