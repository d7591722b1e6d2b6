// The keyframe graph built from the filter's records, and the correction handed back (keyframe_graph.h).
#include "omnislam/smoothing/keyframe_graph.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

namespace omnislam::smoothing {

KeyframeGraph::KeyframeGraph(const GraphOptions& options) : options_(options) {}

void KeyframeGraph::add(KeyframeRecord record) { records_.push_back(std::move(record)); }

namespace {

/// Whether the options ask for, and the motion model allows, the odometry calibration.
bool calibrates(const GraphOptions& o) {
  return o.calibrate_odometry && o.motion.model == slam::MotionNoiseModel::kChord && o.motion.trans_sigma_per_m > 0.0 &&
         o.motion.rot_sigma_per_m > 0.0;
}

}  // namespace

void KeyframeGraph::adoptSolution(const std::vector<Pose2>& poses, const Pose2& T_corr) {
  for (std::size_t k = 0; k < records_.size(); ++k) {
    if (k < poses.size()) records_[k].T_WtoR_smoothed = poses[k];
    else records_[k].T_WtoR_filter = T_corr.compose(records_[k].T_WtoR_filter);
  }
}

Pose2 KeyframeGraph::estimate(std::size_t k) const {
  const KeyframeRecord& r = records_[k];
  return r.T_WtoR_smoothed && k + 1 < records_.size() ? *r.T_WtoR_smoothed : r.T_WtoR_filter;
}

Pose2 KeyframeGraph::covariancePoint(std::size_t k, const Pose2& u_measured, const std::vector<Pose2>& estimates,
                                     const std::vector<double>& lengths) const {
  if (options_.odometry_covariance_at == OdometryCovarianceAt::kMeasured) return u_measured;
  const auto w = static_cast<std::size_t>(std::max(0, options_.covariance_window));
  const std::size_t lo = k > w ? k - w : 1, hi = std::min(records_.size() - 1, k + w);
  double sum = 0.0;
  for (std::size_t i = lo; i <= hi; ++i) sum += lengths[i];
  Pose2 at = slam::odometryIncrement(estimates[k - 1], estimates[k]);
  const double d = lengths[k], mean = sum / static_cast<double>(hi - lo + 1);
  if (d > 1e-9) {  // the estimate's direction and rotation, the window's length
    at.x_m *= mean / d;
    at.y_m *= mean / d;
  }
  return at;
}

Graph KeyframeGraph::build(const std::vector<slam::Landmark>& map) const {
  if (records_.empty()) throw std::logic_error("KeyframeGraph::build without keyframes");
  Graph g;
  g.ceiling = options_.ceiling;
  slam::MotionNoiseOptions motion = options_.motion;
  if (calibrates(options_)) {  // the per-run terms become the calibration's priors
    g.odometry_calibration = OdometryCalibrationPrior{motion.trans_sigma_per_m, motion.rot_sigma_per_m};
    motion.trans_sigma_per_m = 0.0;
    motion.rot_sigma_per_m = 0.0;
  }
  std::vector<Pose2> estimates;  // each keyframe's initial estimate, and the lengths between them
  std::vector<double> lengths(records_.size(), 0.0);
  for (std::size_t k = 0; k < records_.size(); ++k) {
    estimates.push_back(estimate(k));
    if (k == 0) continue;
    const Pose2 d = slam::odometryIncrement(estimates[k - 1], estimates[k]);
    lengths[k] = std::hypot(d.x_m, d.y_m);
  }
  for (std::size_t k = 0; k < records_.size(); ++k) {
    const KeyframeRecord& r = records_[k];
    g.keyframes.push_back({k, r.utime, estimates[k]});
    if (k == 0) continue;
    const Pose2 u = slam::odometryIncrement(records_[k - 1].odom_O, r.odom_O);
    const Pose2 at = covariancePoint(k, u, estimates, lengths);
    g.odometry.push_back({static_cast<int>(k - 1), static_cast<int>(k), u, slam::incrementCovariance(at, motion)});
  }
  g.pose_priors.push_back({0, options_.start, options_.start_cov});
  std::map<std::uint64_t, int> index_of_id;
  for (const auto& l : map) {
    index_of_id.emplace(l.id, static_cast<int>(g.landmarks.size()));
    g.landmarks.push_back({l.id, l.kind, l.p_LinW_m});
  }
  for (std::size_t k = 0; k < records_.size(); ++k) {
    const KeyframeRecord& r = records_[k];
    for (std::size_t i = 0; i < r.z.size() && i < r.landmark_of_measurement.size(); ++i) {
      if (r.landmark_of_measurement[i] < 0) continue;
      const auto it = index_of_id.find(static_cast<std::uint64_t>(r.landmark_of_measurement[i]));
      if (it == index_of_id.end() || g.landmarks[it->second].kind != r.z[i].kind) continue;
      g.bearings.push_back({static_cast<int>(k), it->second, r.z[i]});
    }
  }
  return g;
}

slam::MapCorrection correctionFrom(const Graph& graph, const Solution& solution,
                                   const std::vector<slam::Landmark>& map) {
  slam::MapCorrection c;
  const std::size_t last = graph.keyframes.size() - 1;
  c.T_WtoR_filter = graph.keyframes[last].T_WtoR;
  c.T_WtoR_smoothed = solution.keyframe_poses[last];
  std::vector<int> used(graph.landmarks.size(), 0);
  for (std::size_t i = 0; i < graph.bearings.size(); ++i)
    if (solution.bearing_used[i]) ++used[graph.bearings[i].landmark];
  for (std::size_t j = 0; j < graph.landmarks.size(); ++j) {
    if (used[j] < 2) continue;  // not located by this solve: it moves with the correction
    slam::SmoothedLandmark s;
    s.id = graph.landmarks[j].id;
    s.p_LinW_m = solution.landmarks_m[j];
    const bool have_cov = j < solution.landmark_cov_m2.size() && !solution.landmark_cov_m2[j].isZero(0.0);
    s.cov_LinW_m2 = have_cov ? solution.landmark_cov_m2[j] : map[j].cov_LinW_m2;
    c.landmarks.push_back(s);
  }
  std::sort(c.landmarks.begin(), c.landmarks.end(),
            [](const slam::SmoothedLandmark& a, const slam::SmoothedLandmark& b) { return a.id < b.id; });
  return c;
}

}  // namespace omnislam::smoothing
