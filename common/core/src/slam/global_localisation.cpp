// Global localisation (global_localisation.h): seeds from pairs of bearings matched against the map's
// pair distances, hypotheses tracked with the odometry and scored by their likelihood, the state.
#include "omnislam/core/slam/global_localisation.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "omnislam/core/slam/chi_square.h"
#include "omnislam/core/slam/options_table.h"

namespace omnislam::slam {

std::string GlobalLocalisationOptions::validate() const {
  const std::string ranges = options::checkRanges(*this, options::globalLocalisationFields());
  if (!ranges.empty()) return ranges;
  if (min_matched > max_seed_bearings)
    return "min_matched (" + std::to_string(min_matched) + ") must be <= max_seed_bearings (" +
           std::to_string(max_seed_bearings) + ")";
  if (drop_likelihood_ratio < ambiguity_likelihood_ratio)
    return "drop_likelihood_ratio must be >= ambiguity_likelihood_ratio (a hypothesis that explains the data "
           "is never dropped)";
  return "";
}

const char* localisationStateName(LocalisationState s) {
  switch (s) {
    case LocalisationState::kSearching: return "searching";
    case LocalisationState::kAmbiguous: return "ambiguous";
    case LocalisationState::kLocalised: return "localised";
    case LocalisationState::kLost: return "lost";
  }
  return "unknown";
}

namespace {

const GlobalLocalisationOptions& checked(const GlobalLocalisationOptions& o, const MotionNoiseOptions& m,
                                         const PerceptionOptions& p) {
  for (const std::string& e : {o.validate(), m.validate(), p.validate()})
    if (!e.empty()) throw std::invalid_argument("GlobalLocaliser: " + e);
  return o;
}

bool poseLess(const PoseHypothesis& a, const PoseHypothesis& b) {
  if (a.log_likelihood != b.log_likelihood) return a.log_likelihood > b.log_likelihood;
  if (a.pose_W.x_m != b.pose_W.x_m) return a.pose_W.x_m < b.pose_W.x_m;
  if (a.pose_W.y_m != b.pose_W.y_m) return a.pose_W.y_m < b.pose_W.y_m;
  return a.pose_W.theta_rad < b.pose_W.theta_rad;
}

}  // namespace

GlobalLocaliser::GlobalLocaliser(const GlobalLocalisationOptions& options, const MotionNoiseOptions& motion,
                                 const PerceptionOptions& perception, const std::vector<Landmark>& map)
    : opt_(checked(options, motion, perception)),
      motion_(motion),
      perception_(perception),
      index_(map, options.height_tolerance_m, 2.0 * options.max_range_m, std::max(options.max_range_m / 4.0, 0.5)) {
  gate_bearing_sq_ = chiSquareQuantile(opt_.gate_probability, 2.0);
  count_gate_sq_ = chiSquareQuantile(1.0 - (1.0 - opt_.gate_probability) * (1.0 - opt_.gate_probability), 2.0);
  gate_distance_sigmas_ = std::sqrt(chiSquareQuantile(opt_.gate_probability, 1.0));
  gate_pose_sq_ = chiSquareQuantile(opt_.gate_probability, 3.0);
  // The window's extent in (azimuth, elevation) [rad^2]: clutter is uniform over it.
  const double area =
      2.0 * perception_.azimuth_half_width_rad * (perception_.max_elevation_rad - perception_.min_elevation_rad);
  log_clutter_density_ = std::log(opt_.clutter_per_frame / std::max(area, 1e-6));
  while (max_unexplained_ < 100000 && countsConsistent(0, 0, max_unexplained_)) ++max_unexplained_;
}

const LocalisationStatus& GlobalLocaliser::step(const Pose2& odom_prev, const Pose2& odom_now,
                                                const std::vector<BearingMeasurement>& z) {
  status_.capped = false;
  if (status_.frames > 0) predictTracks(odom_prev, odom_now);
  window_.push_back({odom_now, z});
  if (window_.size() > static_cast<std::size_t>(opt_.window_frames)) window_.erase(window_.begin());
  updateTracks(z);
  addSeeds(z);
  pruneAndSort();
  decide(z);
  return status_;
}

void GlobalLocaliser::predictTracks(const Pose2& odom_prev, const Pose2& odom_now) {
  const Pose2 u = odometryIncrement(odom_prev, odom_now);
  const double d = std::hypot(u.x_m, u.y_m);
  for (PoseHypothesis& h : tracks_) {
    const Eigen::Matrix3d R_W = motionCovariance(h.pose_W, u, motion_);
    h.cov = propagatePoseCovariance(h.pose_W, h.cov, u, R_W);
    h.pose_W = predictPose(h.pose_W, u);
    h.travel_m += d;
  }
}

void GlobalLocaliser::updateTracks(const std::vector<BearingMeasurement>& z) {
  for (PoseHypothesis& h : tracks_) {
    const Fit f = fit(h.pose_W, h.cov, true, z);
    if (f.ok) h.pose_W = f.pose_W, h.cov = f.cov;
    h.frame_llr.push_back(f.llr);
    h.frame_count_llr.push_back(f.count_llr);
    if (h.frame_llr.size() > static_cast<std::size_t>(opt_.window_frames)) {
      h.frame_llr.erase(h.frame_llr.begin());
      h.frame_count_llr.erase(h.frame_count_llr.begin());
    }
    h.log_likelihood = h.count_log_likelihood = 0.0;
    for (double l : h.frame_llr) h.log_likelihood += l;
    for (double c : h.frame_count_llr) h.count_log_likelihood += c;
    h.evidence = opt_.evidence_memory * h.evidence + f.llr;
    h.matched_last = f.matched;
    if (f.matched > 0) ++h.frames_explained;
    if (!consistent(f)) h.evidence = -1.0;  // dropped by pruneAndSort
  }
}

bool GlobalLocaliser::sameHypothesis(const PoseHypothesis& a, const PoseHypothesis& b) const {
  const Eigen::Vector3d d(a.pose_W.x_m - b.pose_W.x_m, a.pose_W.y_m - b.pose_W.y_m,
                          wrapAngle(a.pose_W.theta_rad - b.pose_W.theta_rad));
  const Eigen::Matrix3d S = a.cov + b.cov;
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(S);
  if (!lu.isInvertible()) return d.norm() == 0.0;
  return d.dot(lu.solve(d)) <= gate_pose_sq_;
}

void GlobalLocaliser::addSeeds(const std::vector<BearingMeasurement>& z) {
  std::vector<PoseHypothesis> born;
  auto known = [&](const PoseHypothesis& h) {
    for (const PoseHypothesis& t : tracks_)
      if (sameHypothesis(h, t)) return true;
    return false;
  };
  std::vector<int> scratch;
  const FramePoints pts = framePoints(z);
  for (const Seed& s : seedPoses(z, pts)) {
    PoseHypothesis raw;
    raw.pose_W = s.pose_W, raw.cov = s.cov;
    if (known(raw)) continue;
    bool dup = false;
    for (const PoseHypothesis& b : born) dup = dup || sameHypothesis(raw, b);
    if (dup || !plausibleSeed(s, z, pts, scratch)) continue;
    const Fit f = fit(s.pose_W, s.cov, false, z);
    if (!f.ok || f.matched < opt_.min_matched || !(f.llr > 0.0) || !consistent(f)) continue;
    PoseHypothesis h;
    h.pose_W = f.pose_W, h.cov = f.cov, h.evidence = f.llr, h.log_likelihood = f.llr, h.frame_llr = {f.llr};
    h.count_log_likelihood = f.count_llr, h.frame_count_llr = {f.count_llr};
    h.frames_explained = 1, h.matched_last = f.matched;
    if (known(h) || !runBackwards(h)) continue;
    auto same = std::find_if(born.begin(), born.end(), [&](const PoseHypothesis& b) { return sameHypothesis(h, b); });
    if (same == born.end()) born.push_back(h);
    else if (poseLess(h, *same)) *same = h;
  }
  tracks_.insert(tracks_.end(), born.begin(), born.end());
}

bool GlobalLocaliser::runBackwards(PoseHypothesis& h) const {
  const PoseHypothesis* best = nullptr;  // the best tracked one over the window
  for (const PoseHypothesis& t : tracks_)
    if (!best || t.log_likelihood > best->log_likelihood) best = &t;
  const double margin = std::log(opt_.drop_likelihood_ratio);
  Pose2 x = h.pose_W;
  Eigen::Matrix3d P = h.cov;
  Pose2 first_back_pose;  // the pose and covariance at the frame before this one
  Eigen::Matrix3d first_back_cov = Eigen::Matrix3d::Zero();
  double best_sum = best && !best->frame_llr.empty() ? best->frame_llr.back() : 0.0, sum = h.frame_llr.back();
  double best_csum = best && !best->frame_count_llr.empty() ? best->frame_count_llr.back() : 0.0;
  double csum = h.frame_count_llr.back();
  // Dropped only when it is worse by the margin in L and in C (shared map error: the file header).
  const auto worse = [&] { return best && sum < best_sum - margin && csum < best_csum - margin; };
  for (std::size_t back = 1; back < window_.size(); ++back) {
    const PastFrame& later = window_[window_.size() - back];
    const PastFrame& frame = window_[window_.size() - back - 1];
    const Pose2 u = odometryIncrement(later.odom, frame.odom);
    P = propagatePoseCovariance(x, P, u, motionCovariance(x, u, motion_));
    x = predictPose(x, u);
    const Fit f = fit(x, P, true, frame.z);
    if (f.ok) x = f.pose_W, P = f.cov;
    if (back == 1) first_back_pose = x, first_back_cov = P;
    h.frame_llr.insert(h.frame_llr.begin(), f.llr);
    h.frame_count_llr.insert(h.frame_count_llr.begin(), f.count_llr);
    sum += f.llr, csum += f.count_llr;
    // Its L and C sum these frames, but frames_explained and travel_m count from its birth forward:
    // a pose fitted to this frame and run back through the window follows that window's odometry
    // by construction, so those frames rank it and cannot confirm it (issue 56, halls 28: a seed 22.6 m
    // off, born in frame 7, was confirmed by the six frames before it in that same frame).
    if (best && best->frame_llr.size() > back) {
      best_sum += best->frame_llr[best->frame_llr.size() - 1 - back];
      best_csum += best->frame_count_llr[best->frame_count_llr.size() - 1 - back];
    }
    if (worse()) return false;
  }
  // The birth frame scored as the tracked ones are: predicted from the frame before (not fitted to
  // itself, which would favour a seed by the prediction's own uncertainty).
  if (window_.size() > 1) {
    const Pose2 u = odometryIncrement(window_[window_.size() - 2].odom, window_.back().odom);
    Pose2 x1 = first_back_pose;
    const Eigen::Matrix3d P1 = propagatePoseCovariance(x1, first_back_cov, u, motionCovariance(x1, u, motion_));
    x1 = predictPose(x1, u);
    const Fit now = fit(x1, P1, true, window_.back().z);
    sum += now.llr - h.frame_llr.back(), csum += now.count_llr - h.frame_count_llr.back();
    h.frame_llr.back() = now.llr, h.frame_count_llr.back() = now.count_llr;
    if (worse()) return false;
  }
  h.log_likelihood = sum, h.count_log_likelihood = csum;
  return true;
}

double GlobalLocaliser::bestCount() const {
  double c = -std::numeric_limits<double>::infinity();
  for (const PoseHypothesis& h : tracks_) c = std::max(c, h.count_log_likelihood);
  return c;
}

void GlobalLocaliser::pruneAndSort() {
  tracks_.erase(
      std::remove_if(tracks_.begin(), tracks_.end(),
                     [](const PoseHypothesis& h) { return !(h.evidence >= 0.0) || !h.pose_W.vec().allFinite(); }),
      tracks_.end());
  std::sort(tracks_.begin(), tracks_.end(), poseLess);
  if (tracks_.empty()) return;
  // Dropped for its L only when its C is also below the best C by the ratio (shared map error).
  const double floor = tracks_.front().log_likelihood - std::log(opt_.drop_likelihood_ratio);
  const double count_floor = bestCount() - std::log(opt_.drop_likelihood_ratio);
  tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(),
                               [&](const PoseHypothesis& h) {
                                 return h.log_likelihood < floor && h.count_log_likelihood < count_floor;
                               }),
                tracks_.end());
  if (tracks_.size() > static_cast<std::size_t>(opt_.max_hypotheses)) {
    tracks_.resize(static_cast<std::size_t>(opt_.max_hypotheses));
    status_.capped = true;
  }
}

void GlobalLocaliser::decide(const std::vector<BearingMeasurement>& z) {
  ++status_.frames;
  status_.num_tracked = static_cast<int>(tracks_.size());
  status_.best.assign(
      tracks_.begin(),
      tracks_.begin() + std::min<std::ptrdiff_t>(opt_.max_reported, static_cast<std::ptrdiff_t>(tracks_.size())));
  if (tracks_.empty()) {
    const auto points =
        std::count_if(z.begin(), z.end(), [](const BearingMeasurement& m) { return m.kind == LandmarkKind::kPoint3D; });
    status_.num_hypotheses = 0;
    if (had_hypotheses_ || points >= opt_.min_matched) status_.state = LocalisationState::kLost;
    return;  // searching stays searching, lost stays lost
  }
  had_hypotheses_ = true;
  // Within the ambiguity ratio of the best in L, or within the drop ratio of the best C (the counts:
  // shared map error, the file header; the wider ratio because a lamp at the edge of the range or a
  // gate, matched for one pose and not for its twin, is worth a match, ~10 nats, for the whole window).
  const double floor = tracks_.front().log_likelihood - std::log(opt_.ambiguity_likelihood_ratio);
  const double count_floor = bestCount() - std::log(opt_.drop_likelihood_ratio);
  status_.num_hypotheses = static_cast<int>(std::count_if(tracks_.begin(), tracks_.end(), [&](const PoseHypothesis& h) {
    return h.log_likelihood >= floor || h.count_log_likelihood >= count_floor;
  }));
  const PoseHypothesis& best = tracks_.front();
  const bool confirmed = best.frames_explained >= opt_.min_frames && best.travel_m >= opt_.min_travel_m;
  if (status_.num_hypotheses > 1) status_.state = LocalisationState::kAmbiguous;
  else if (confirmed && !status_.capped) status_.state = LocalisationState::kLocalised;
  else status_.state = LocalisationState::kSearching;
}

}  // namespace omnislam::slam
