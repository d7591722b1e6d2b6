// The localising phase of a run with no start pose: see global_start.h and
// docs/design/global-localisation.md ("In the SLAM process").
#include "omnislam/runtime/global_start.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace omnislam::runtime {

namespace {

std::vector<slam::Landmark> withPoints(std::vector<slam::Landmark> map) {
  const bool any = std::any_of(map.begin(), map.end(),
                               [](const slam::Landmark& l) { return l.kind == slam::LandmarkKind::kPoint3D; });
  if (!any)
    throw std::invalid_argument(
        "global localisation (start_pose.source unknown, lost.policy relocalise): the loaded map has no point "
        "landmarks (ceiling lights) to localise against");
  return map;
}

}  // namespace

GlobalStart::GlobalStart(const slam::GlobalLocalisationOptions& options, const slam::FastSlamOptions& filter,
                         std::vector<slam::Landmark> map)
    : opt_(options), filter_(filter), map_(withPoints(std::move(map))) {
  restart();  // builds the first localiser: invalid options throw here, at start
}

void GlobalStart::restart() {
  localiser_ = std::make_unique<slam::GlobalLocaliser>(opt_, filter_.motion, filter_.perception, map_);
  has_prev_ = false;
  status_ = slam::LocalisationStatus{};
  phase_ = Phase::kLocalising;
}

void GlobalStart::restart(std::vector<slam::Landmark> map) {
  map_ = withPoints(std::move(map));
  restart();
}

std::optional<GlobalStart::Fix> GlobalStart::onFrame(const Pose2& odom_O,
                                                     const std::vector<slam::BearingMeasurement>& z) {
  if (phase_ != Phase::kLocalising) throw std::logic_error("GlobalStart::onFrame while tracking");
  // The first frame of a localiser has no motion before it (odom_prev = odom_now).
  status_ = localiser_->step(has_prev_ ? odom_prev_O_ : odom_O, odom_O, z);
  odom_prev_O_ = odom_O;
  has_prev_ = true;
  ++frames_;
  if (status_.state != slam::LocalisationState::kLocalised || status_.best.empty()) return std::nullopt;
  ++fixes_;
  phase_ = Phase::kTracking;
  localiser_.reset();  // its hypotheses are no longer needed; a restart builds a new one
  return Fix{status_.best.front().pose_W, status_.best.front().cov};
}

slam_localisation_t toLocalisationMessage(const slam::LocalisationStatus& s, int64_t utime, int64_t seq,
                                          int64_t input_seq) {
  slam_localisation_t m{};
  m.utime = utime;
  m.seq = seq;
  m.input_seq = input_seq;
  m.state = static_cast<int8_t>(s.state);
  m.num_hypotheses = s.num_hypotheses;
  m.num_tracked = s.num_tracked;
  m.num_frames = s.frames;
  m.num_reported = static_cast<int32_t>(s.best.size());
  const double best_ll = s.best.empty() ? 0.0 : s.best.front().log_likelihood;
  for (const slam::PoseHypothesis& h : s.best) {
    m.x_m.push_back(h.pose_W.x_m);
    m.y_m.push_back(h.pose_W.y_m);
    m.theta_rad.push_back(h.pose_W.theta_rad);
    std::vector<double> cov(9);
    for (int k = 0; k < 9; ++k) cov[static_cast<std::size_t>(k)] = h.cov(k / 3, k % 3);
    m.covariance.push_back(std::move(cov));
    // The best first: 0 for it, <= 0 for the others (a rounding above 0 would be refused).
    m.relative_log_likelihood.push_back(std::min(0.0, h.log_likelihood - best_ll));
    m.frames_explained.push_back(h.frames_explained);
    m.travel_m.push_back(h.travel_m);
  }
  return m;
}

}  // namespace omnislam::runtime
