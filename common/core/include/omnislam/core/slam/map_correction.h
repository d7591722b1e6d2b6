// A correction of the filter's estimate by a smoother (common/smoothing): the smoothed landmarks and
// the smoothed pose of one keyframe, and how the filter's landmarks, candidates and poses move onto
// them. The correction is a rigid motion of W, T_corr = T_smoothed * T_filter^-1, taken at the
// keyframe the smoother solved: what the filter did since that keyframe moves with it, and the
// landmarks the smoother solved take their smoothed means and marginal covariances.
// docs/design/smoothing.md, "Handing the map back".
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/candidate.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::slam {

struct SmoothedLandmark {
  std::uint64_t id = 0;  ///< the filter's landmark id
  Eigen::Vector3d p_LinW_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov_LinW_m2 = Eigen::Matrix3d::Identity();  ///< marginal covariance [m^2], PD
};

struct MapCorrection {
  Pose2 T_WtoR_filter;                      ///< the filter's pose at the solved keyframe (the smoother's start)
  Pose2 T_WtoR_smoothed;                    ///< the smoother's pose of that keyframe
  std::vector<SmoothedLandmark> landmarks;  ///< sorted by id
};

/// T_corr = T_WtoR_smoothed * T_WtoR_filter^-1: the rigid motion of W that takes the filter's pose
/// at the keyframe to the smoothed one.
Pose2 correctionTransform(const MapCorrection& c);

/// A landmark moved by the rigid motion T (x-y rotated and translated, z kept; covariance rotated).
Landmark transformLandmark(const Landmark& l, const Pose2& T);

/// A candidate's rays and estimate moved by the rigid motion T (the measurements stay: they are in
/// robot axes).
Candidate transformCandidate(const Candidate& c, const Pose2& T);

/// The corrected landmark set: each landmark of `map` with a smoothed counterpart (same id) takes
/// its mean and covariance; the others move by correctionTransform(c). Order and ids kept.
std::vector<Landmark> correctLandmarks(const std::vector<Landmark>& map, const MapCorrection& c);

}  // namespace omnislam::slam
