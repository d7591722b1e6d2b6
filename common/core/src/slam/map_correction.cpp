// Moving the filter's landmarks, candidates and poses onto a smoother's solution (map_correction.h).
#include "omnislam/core/slam/map_correction.h"

#include <algorithm>
#include <cmath>

namespace omnislam::slam {
namespace {

Eigen::Matrix3d rotationZ(double theta_rad) {
  const double c = std::cos(theta_rad), s = std::sin(theta_rad);
  Eigen::Matrix3d R;
  R << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
  return R;
}

Eigen::Vector3d transformPoint(const Eigen::Vector3d& p, const Pose2& T) {
  const Eigen::Vector2d xy = T.transformFrom(p.head<2>());
  return {xy.x(), xy.y(), p.z()};
}

}  // namespace

Pose2 correctionTransform(const MapCorrection& c) { return c.T_WtoR_smoothed.compose(c.T_WtoR_filter.inverse()); }

Landmark transformLandmark(const Landmark& l, const Pose2& T) {
  Landmark out = l;
  const Eigen::Matrix3d R = rotationZ(T.theta_rad);
  out.p_LinW_m = transformPoint(l.p_LinW_m, T);
  out.cov_LinW_m2 = R * l.cov_LinW_m2 * R.transpose();
  return out;
}

Candidate transformCandidate(const Candidate& c, const Pose2& T) {
  Candidate out = c;
  const Eigen::Matrix3d R = rotationZ(T.theta_rad);
  for (auto& o : out.observations) {
    o.T_WtoR = T.compose(o.T_WtoR);
    o.p_CinW_m = transformPoint(o.p_CinW_m, T);
    o.dir_W = R * o.dir_W;
    o.cos_theta = std::cos(o.T_WtoR.theta_rad);
    o.sin_theta = std::sin(o.T_WtoR.theta_rad);
  }
  if (out.has_estimate) {
    out.estimate_W_m = transformPoint(c.estimate_W_m, T);
    out.estimate_cov_m2 = R * c.estimate_cov_m2 * R.transpose();
  }
  return out;
}

std::vector<Landmark> correctLandmarks(const std::vector<Landmark>& map, const MapCorrection& c) {
  const Pose2 T = correctionTransform(c);
  std::vector<Landmark> out;
  out.reserve(map.size());
  for (const auto& l : map) {
    const auto it = std::lower_bound(c.landmarks.begin(), c.landmarks.end(), l.id,
                                     [](const SmoothedLandmark& s, std::uint64_t id) { return s.id < id; });
    if (it != c.landmarks.end() && it->id == l.id) {
      Landmark s = l;
      s.p_LinW_m = l.kind == LandmarkKind::kPoint3D
                       ? it->p_LinW_m
                       : Eigen::Vector3d(it->p_LinW_m.x(), it->p_LinW_m.y(), l.p_LinW_m.z());
      s.cov_LinW_m2 = it->cov_LinW_m2;
      if (l.kind == LandmarkKind::kVerticalLine) s.cov_LinW_m2(2, 2) = l.cov_LinW_m2(2, 2);
      out.push_back(s);
    } else {
      out.push_back(transformLandmark(l, T));
    }
  }
  return out;
}

}  // namespace omnislam::slam
