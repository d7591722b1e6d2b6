// Landmark types I and II (paper 000, Sec. III-F 2), the one place of the rule: assigned when a
// candidate is initialised (candidate.cpp), used by the proposal and the weight, promoted after updates.
//
// A landmark is type I when the robot poses it is judged from are all within D_min of it in the x-y
// plane of W (the paper: the two poses of its best cross-point at initialisation; later, any pose it
// is observed from). Only type I landmarks correct the pose (Alg. 3 lines 6-11) and weigh the
// particle (Alg. 4 lines 11-17); type II landmarks are associated and updated all the same.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::slam {

/// Whether the robot at T_WtoR is near enough to the landmark at p_LinW_m for type I:
/// |p_xy - T_xy| < d_min_m [m].
inline bool withinTypeIDistance(const Pose2& T_WtoR, const Eigen::Vector3d& p_LinW_m, double d_min_m) {
  return std::hypot(p_LinW_m.x() - T_WtoR.x_m, p_LinW_m.y() - T_WtoR.y_m) < d_min_m;
}

/// Type at initialisation from the two poses of the cross-point (updateCandidateLandmarks()).
inline LandmarkType initialLandmarkType(const Pose2& T_a, const Pose2& T_b, const Eigen::Vector3d& p_LinW_m,
                                        double d_min_m) {
  const bool near = withinTypeIDistance(T_a, p_LinW_m, d_min_m) && withinTypeIDistance(T_b, p_LinW_m, d_min_m);
  return near ? LandmarkType::kTypeI : LandmarkType::kTypeII;
}

/// updateLandmarksType(): a type II landmark observed from x_t within D_min becomes type I (never back).
inline LandmarkType promotedLandmarkType(const Landmark& updated, const Pose2& x_t, double d_min_m) {
  if (updated.type == LandmarkType::kTypeII && withinTypeIDistance(x_t, updated.p_LinW_m, d_min_m)) {
    return LandmarkType::kTypeI;
  }
  return updated.type;
}

/// Whether the landmark takes part in the proposal (Alg. 3 line 7) and the weight (Alg. 4 line 11).
inline bool correctsPoseAndWeighs(const Landmark& l) { return l.type == LandmarkType::kTypeI; }

}  // namespace omnislam::slam
