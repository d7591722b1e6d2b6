// What the viewer has seen, bounded, turned into view data: see viewer_state.h.
#include "viewer_state.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "omnislam/lcmio/image_msg.h"

namespace omnislam::viewer {
namespace {

Pose2 toPose2(const pose_t& m) { return {m.x_m, m.y_m, m.theta_rad}; }

std::string fmt(const char* f, double a) {
  char b[64];
  std::snprintf(b, sizeof b, f, a);
  return b;
}

template <class T>
void pushBounded(std::deque<T>& q, T v, size_t cap) {
  q.push_back(std::move(v));
  while (q.size() > std::max<size_t>(1, cap)) q.pop_front();
}

}  // namespace

ViewerState::ViewerState(ViewerStateOptions opt)
    : opt_(opt), est_track_(opt.max_track_points), truth_track_(opt.max_track_points) {}

void ViewerState::onSlamPose(const pose_t& m) {
  if (first_utime_ < 0) first_utime_ = m.utime;
  if (pose_ && m.utime < pose_->utime) est_track_.clear();  // a replay restarted: a new trajectory
  pose_ = m;
  ++steps_;
  est_track_.add(toPose2(m));
}

void ViewerState::onSlamMap(const map_t& m) { map_ = m; }
void ViewerState::onParticles(const particles_t& m) { particles_ = m; }
void ViewerState::onAssociations(const associations_t& m) { pushBounded(assocs_, m, opt_.recent_frames); }

void ViewerState::onTruthPose(const pose_t& m) {
  if (first_utime_ < 0) first_utime_ = m.utime;
  if (truth_now_ && m.utime < truth_now_->utime) {
    truth_track_.clear();
    truth_recent_.clear();
  }
  truth_now_ = m;
  truth_track_.add(toPose2(m));
  pushBounded(truth_recent_, m, opt_.truth_history);
}

void ViewerState::onTruthMap(const map_t& m) { truth_map_ = m; }

void ViewerState::onLocalisation(const slam_localisation_t& m) {
  if (first_utime_ < 0) first_utime_ = m.utime;
  localisation_ = m;
}

void ViewerState::setSavedMap(std::vector<vision::ViewLandmark> landmarks, std::string name) {
  saved_map_ = std::move(landmarks);
  saved_map_name_ = std::move(name);
}

bool ViewerState::localising() const { return localisation_ && (!pose_ || localisation_->utime > pose_->utime); }

bool ViewerState::onImage(const image_t& m, std::string* why) {
  auto img = lcmio::decodeImage(m, why);
  if (!img) return false;
  cv::Mat mat = *img;
  if (mat.channels() == 4) cv::cvtColor(mat, mat, cv::COLOR_BGRA2BGR);
  if (mat.type() != CV_8UC1 && mat.type() != CV_8UC3) {
    if (why) *why = "unsupported image type (need 8-bit grey or colour)";
    return false;
  }
  if (first_utime_ < 0) first_utime_ = m.utime;
  ++images_seen_;
  pushBounded(images_, Image{m.utime, m.seq, mat}, opt_.recent_frames);
  return true;
}

void ViewerState::onFeatures(const features_t& m) {
  Frame f;
  f.utime = m.utime;
  f.seq = m.seq;
  f.features.reserve(m.features.size());
  for (const auto& x : m.features) {
    vision::ViewFeature v;
    v.u_px = x.u_px;
    v.v_px = x.v_px;
    v.kind = x.kind;
    f.features.push_back(v);
  }
  ++frames_seen_;
  pushBounded(frames_, std::move(f), opt_.recent_frames);
}

const associations_t* ViewerState::findAssociations(const Frame& f) const {
  const associations_t* by_time = nullptr;
  for (auto it = assocs_.rbegin(); it != assocs_.rend(); ++it) {
    if (it->utime != f.utime || it->num_features != static_cast<int32_t>(f.features.size())) continue;
    if (it->input_seq == f.seq) return &*it;
    if (!by_time) by_time = &*it;
  }
  return by_time;
}

const ViewerState::Image* ViewerState::findImage(int64_t utime) const {
  for (auto it = images_.rbegin(); it != images_.rend(); ++it)
    if (it->utime == utime) return &*it;
  return nullptr;
}

double ViewerState::relativeS(int64_t utime) const {
  const double t0 = first_utime_ < 0 ? 0.0 : static_cast<double>(first_utime_);
  return (static_cast<double>(utime) - t0) * 1e-6;
}

const pose_t* ViewerState::truthNear(int64_t utime) const {
  const pose_t* best = nullptr;
  for (const auto& t : truth_recent_)
    if (!best || std::llabs(t.utime - utime) < std::llabs(best->utime - utime)) best = &t;
  return best;
}

// Trajectories and poses: the true pose at the estimate's time (the nearest held), so that both
// arrows match; while localising, at the localiser's latest frame.
void ViewerState::addPoses(vision::SlamViewData& d) const {
  d.estimate_track = est_track_.points();
  d.truth_track = truth_track_.points();
  if (pose_) {
    d.pose = toPose2(*pose_);
    d.pose_cov_xy_m2 << pose_->covariance[0][0], pose_->covariance[0][1], pose_->covariance[1][0],
        pose_->covariance[1][1];
  }
  const pose_t* truth = nullptr;
  if (localising()) truth = truthNear(localisation_->utime);
  else if (pose_) truth = truthNear(pose_->utime);
  if (!truth && truth_now_) truth = &*truth_now_;
  if (truth) d.true_pose = toPose2(*truth);
}

// Maps and particles.
void ViewerState::addMaps(vision::SlamViewData& d) const {
  if (!map_) d.landmarks = saved_map_;
  if (map_) {
    for (const auto& l : map_->landmarks) {
      vision::ViewLandmark v;
      v.id = l.id;
      v.p_m = Eigen::Vector3d(l.position_m[0], l.position_m[1], l.position_m[2]);
      v.cov_xy_m2 << l.covariance[0][0], l.covariance[0][1], l.covariance[1][0], l.covariance[1][1];
      v.type = l.type;
      v.kind = l.kind;
      d.landmarks.push_back(v);
    }
  }
  if (truth_map_)
    for (const auto& l : truth_map_->landmarks)
      d.true_landmarks.emplace_back(l.position_m[0], l.position_m[1], l.position_m[2]);
  if (particles_) {
    const size_t n = std::min(
        {particles_->x_m.size(), particles_->y_m.size(), particles_->theta_rad.size(), particles_->weight.size()});
    for (size_t i = 0; i < n; ++i)
      d.particles.push_back(
          {{particles_->x_m[i], particles_->y_m[i], particles_->theta_rad[i]}, particles_->weight[i]});
  }
}

// Status lines: time, step, particles, the estimate and its error, landmark counts.
void ViewerState::addStatusLines(vision::SlamViewData& d) const {
  if (pose_) {
    std::string l1 = "t " + fmt("%.1f s", relativeS(pose_->utime)) + "   step " + std::to_string(steps_) + "   " +
                     std::to_string(pose_->num_particles) + " particles, ESS " +
                     fmt("%.1f", pose_->effective_sample_size);
    d.info.push_back(l1);
    std::string l2 = "estimate x " + fmt("%.2f", pose_->x_m) + " m, y " + fmt("%.2f", pose_->y_m) + " m, heading " +
                     fmt("%.1f deg", pose_->theta_rad * 180.0 / M_PI);
    if (d.true_pose)
      l2 += "   |  error " + fmt("%.2f m", std::hypot(pose_->x_m - d.true_pose->x_m, pose_->y_m - d.true_pose->y_m)) +
            ", " + fmt("%.1f deg", std::abs(wrapAngle(pose_->theta_rad - d.true_pose->theta_rad)) * 180.0 / M_PI);
    d.info.push_back(l2);
  } else {
    d.info.push_back(truth_now_ ? "t " + fmt("%.1f s", relativeS(truth_now_->utime)) + "   waiting for SLAM_POSE"
                                : std::string("waiting for SLAM_POSE"));
  }
  int type1 = 0, type2 = 0;
  for (const auto& l : d.landmarks) {
    type1 += l.type == 1;
    type2 += l.type == 2;
  }
  std::string l3 = "landmarks " + std::to_string(d.landmarks.size()) + " (type I " + std::to_string(type1) +
                   ", type II " + std::to_string(type2) + ")";
  if (map_) l3 += ", candidates " + std::to_string(map_->num_candidates);
  else if (!saved_map_.empty()) l3 += ", the saved map " + saved_map_name_;
  if (truth_map_) l3 += ", true " + std::to_string(d.true_landmarks.size());
  d.info.push_back(l3);
}

// The frame to show: the one the latest SLAM step answered, else the latest features frame with its
// image, else the latest image; its features coloured by their associations.
void ViewerState::addFrame(vision::SlamViewData& d) const {
  const Frame* frame = nullptr;
  const Image* image = nullptr;
  if (pose_)
    for (auto it = frames_.rbegin(); it != frames_.rend() && !frame; ++it)
      if (it->utime == pose_->utime && (image = findImage(it->utime))) frame = &*it;
  for (auto it = frames_.rbegin(); it != frames_.rend() && !frame; ++it)
    if ((image = findImage(it->utime))) frame = &*it;
  if (!frame && !images_.empty()) image = &images_.back();
  if (image) {
    d.image = image->mat;
    d.image_caption = "image seq " + std::to_string(image->seq) + ", t " + fmt("%.1f s", relativeS(image->utime));
  }
  if (frame) {
    d.features = frame->features;
    const associations_t* a = findAssociations(*frame);
    int assoc = 0, cand = 0, unused = 0;
    if (a) {
      for (size_t i = 0; i < d.features.size() && i < a->landmark_id.size(); ++i) {
        d.features[i].landmark_id = a->landmark_id[i];
        assoc += a->landmark_id[i] >= 0;
        cand += a->landmark_id[i] == associations_t::NOT_ASSOCIATED;
        unused += a->landmark_id[i] == associations_t::NOT_USED;
      }
    }
    d.image_caption += ",  " + std::to_string(d.features.size()) + " features";
    if (a)
      d.image_caption += ": " + std::to_string(assoc) + " associated, " + std::to_string(cand) + " to candidates, " +
                         std::to_string(unused) + " not used";
    else d.image_caption += " (no associations for this frame)";
  }
}

// The global localiser: its state in a status line (whenever it has spoken), its hypotheses while it
// is localising.
void ViewerState::addLocalisation(vision::SlamViewData& d) const {
  if (!localisation_) return;
  const slam_localisation_t& m = *localisation_;
  static const char* const kStates[] = {"SEARCHING", "AMBIGUOUS", "LOCALISED", "LOST"};
  const bool known = m.state >= 0 && m.state <= 3;
  std::string line = std::string("localisation: ") + (known ? kStates[m.state] : "?") + " at t " +
                     fmt("%.1f s", relativeS(m.utime)) + ", " + std::to_string(m.num_hypotheses) + " hypotheses (" +
                     std::to_string(m.num_tracked) + " tracked), " + std::to_string(m.num_frames) + " frames";
  if (m.num_reported > 1) line += ", 2nd best " + fmt("%.1f nats", m.relative_log_likelihood[1]);
  d.info.push_back(line);
  if (!localising()) return;
  for (int32_t k = 0; k < m.num_reported; ++k) {
    vision::ViewHypothesis h;
    h.pose = {m.x_m[k], m.y_m[k], m.theta_rad[k]};
    h.cov_xy_m2 << m.covariance[k][0], m.covariance[k][1], m.covariance[k][3], m.covariance[k][4];
    h.relative_log_likelihood = m.relative_log_likelihood[k];
    d.hypotheses.push_back(h);
  }
}

vision::SlamViewData ViewerState::viewData(const std::string& title) const {
  vision::SlamViewData d;
  d.title = title;
  addPoses(d);
  addMaps(d);
  addStatusLines(d);
  addLocalisation(d);
  addFrame(d);
  return d;
}

}  // namespace omnislam::viewer
