// Cross-point of two bearing rays (paper 000, Sec. III-F 1 and Fig. 3): the midpoint of the
// shortest segment between two 3D rays c_i + s_i b_i, with the parallax and a degeneracy check.
#pragma once

#include <Eigen/Core>
#include <optional>

namespace omnislam::slam {

struct RayCrossPoint {
  Eigen::Vector3d p_XinW_m = Eigen::Vector3d::Zero();  ///< midpoint of the shortest segment [m]
  double depth1_m = 0.0;      ///< s_1: distance along ray 1 to its end of the segment (< 0: behind)
  double depth2_m = 0.0;      ///< s_2: same along ray 2
  double gap_m = 0.0;         ///< length of the shortest segment (0 when the rays intersect)
  double parallax_rad = 0.0;  ///< angle between b_1 and b_2, i.e. subtended at the cross-point
};

/// Closest approach of the rays c1 + s b1 and c2 + t b2 (b1, b2 need not be unit). With
/// w = c1 - c2, b = b1.b2, d = b1.w, e = b2.w (unit b's): s = (b e - d) / (1 - b^2),
/// t = (e - b d) / (1 - b^2). Returns std::nullopt when the parallax is below min_parallax_rad
/// (parallel rays: no unique cross-point) or a direction is zero. Depths may be negative; the
/// caller decides whether a point behind a camera is acceptable.
std::optional<RayCrossPoint> crossPointOfRays(const Eigen::Vector3d& c1_W_m, const Eigen::Vector3d& b1_W,
                                              const Eigen::Vector3d& c2_W_m, const Eigen::Vector3d& b2_W,
                                              double min_parallax_rad = 1e-9);

/// Depths along the two rays of their closest approach.
struct RayCrossDepths {
  double depth1_m = 0.0;  ///< RayCrossPoint::depth1_m
  double depth2_m = 0.0;  ///< RayCrossPoint::depth2_m
};

/// crossPointOfRays's depth1_m and depth2_m, bit for bit, and std::nullopt exactly when it returns
/// std::nullopt, without the point, gap and parallax: for a caller that scores many ray pairs
/// (candidate association). The parallax test needs no atan2 unless tan(parallax) is within a
/// factor of 2 of min_parallax_rad (min_parallax_rad < 0.5 rad; otherwise it is always computed).
std::optional<RayCrossDepths> crossDepthsOfRays(const Eigen::Vector3d& c1_W_m, const Eigen::Vector3d& b1_W,
                                                const Eigen::Vector3d& c2_W_m, const Eigen::Vector3d& b2_W,
                                                double min_parallax_rad = 1e-9);

}  // namespace omnislam::slam
