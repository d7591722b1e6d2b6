// Reading the logs omnislam-eval scores (eval_log.h).
#include "eval_log.h"

#include <iostream>

#include "omnislam/associations_t.hpp"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/plausibility.h"
#include "omnislam/lcmio/utime_order.h"
#include "omnislam/lcmio/validate.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/slam_trajectory_t.hpp"

namespace omnislam::evaltool {

namespace {

/// The event as Msg if it decodes and passes lcmio::validate (finite, in range); otherwise counted in
/// c.skipped with the log, the channel and the reason, and nothing.
template <class Msg>
std::optional<Msg> decodeValid(const std::string& path, const lcmio::LogEvent& ev, LogContent& c) {
  std::string why;
  auto m = lcmio::decodeValid<Msg>(ev, &why);
  if (!m) ++c.skipped[path + ": " + ev.channel + ": " + why];
  return m;
}

/// m[utime] = v; a message at a utime already read replaces the earlier one, which is counted in
/// c.skipped (a second run in the same log, or a publisher that repeats itself: never silent).
template <class V>
void keepByUtime(std::map<int64_t, V>& m, int64_t utime, V v, const std::string& path, const std::string& channel,
                 LogContent& c) {
  if (!m.insert_or_assign(utime, std::move(v)).second)
    ++c.skipped[path + ": " + channel + ": utime already read, replaced by this later message"];
}

/// Whether a map message at `utime` is the newest so far (`newest`: the utime of the map kept, or
/// nothing); an older one is counted in c.skipped and left out, one at the same utime replaces it.
bool newestMap(std::optional<int64_t>& newest, int64_t utime, const std::string& path, const std::string& channel,
               LogContent& c) {
  if (newest && utime < *newest) {
    ++c.skipped[path + ": " + channel + ": older than one already read (the newest utime is kept)"];
    return false;
  }
  if (newest && utime == *newest)
    ++c.skipped[path + ": " + channel + ": utime already read, replaced by this later message"];
  newest = utime;
  return true;
}

/// Poses by utime (a later message with the same utime replaces the earlier one), sorted.
std::vector<eval::TimedPose> posesOf(const std::map<int64_t, Pose2>& m) {
  std::vector<eval::TimedPose> out;
  for (const auto& [u, p] : m) out.push_back({u, p});
  return out;
}

/// A SLAM_MAP (with its x-y covariances) or GROUND_TRUTH_MAP event, kept if it is the newest.
void readMap(const std::string& path, const lcmio::LogEvent& ev, bool slam, LogContent& c) {
  auto m = decodeValid<map_t>(path, ev, c);
  if (!m || !newestMap(slam ? c.slam_map_utime : c.truth_map_utime, m->utime, path, ev.channel, c)) return;
  auto& points = slam ? c.slam_map : c.truth_map;
  auto& ids = slam ? c.slam_map_ids : c.truth_map_ids;
  points.clear();
  ids.clear();
  if (slam) c.slam_map_cov_xy.clear();
  for (const auto& l : m->landmarks) {
    ids.push_back(l.id);
    points.emplace_back(l.position_m[0], l.position_m[1], l.position_m[2]);
    if (slam) {
      Eigen::Matrix2d cov;
      cov << l.covariance[0][0], l.covariance[0][1], l.covariance[1][0], l.covariance[1][1];
      c.slam_map_cov_xy.push_back(cov);
    }
  }
  (slam ? c.have_slam_map : c.have_truth_map) = true;
}

/// Poses, odometry and features of a log being read, before they go into LogContent.
struct PoseMaps {
  std::map<int64_t, Pose2> slam, truth, odom;
  lcmio::UtimeOrder truth_order;       ///< the truth's time order (admitTruth)
  lcmio::PoseStreamCheck truth_check;  ///< and its plausibility
  lcmio::UtimeOrder frame_order;       ///< the feature frames' time order (admitFrame)
};

/// Options of the time rule for a recording: a fixed 60 s jump threshold (a gap in a recording is
/// data), the rest as the processes' (docs/user/lcm.md "Time faults").
lcmio::UtimeOrderOptions recordingTimeRule() {
  lcmio::UtimeOrderOptions topt;
  topt.min_forward_jump_us = topt.max_forward_jump_us;
  return topt;
}

/// A feature frame whose utime is a stray (far ahead of or behind its stream, and not continued) is
/// no frame of the run: it is left out of the coverage figures and counted in c.skipped, as the
/// SLAM process refuses it (one frame stamped 1e6 s ahead would otherwise make the run's span
/// 1e6 s and every run "incomplete").
bool admitFrame(int64_t utime, PoseMaps& p, const std::string& path, LogContent& c) {
  if (!p.frame_order.admit(utime, recordingTimeRule())) return true;
  ++c.skipped[path + ": " + channels::kOmniFeatures + ": utime out of order or a stray jump (lcmio::UtimeOrder)"];
  return false;
}

/// The truth is judged as the processes judge it (docs/user/lcm.md "Time faults", docs/user/messages.md
/// "Plausibility"), with bounds for any dataset: a stray stamp (a copy 30 s back would replace the
/// truth of another time) or a pose that jumps faster than 1000 m/s or 100 rad/s (x = 1e300) is
/// left out and counted in c.skipped, never scored against; a refused pose leaves the time order as
/// it was. The time threshold is the fixed 60 s of a recording (a gap in it is data); the
/// coordinates are not bounded (a car's UTM coordinates are 1e5 m and more).
bool admitTruth(const pose_t& m, PoseMaps& p, const std::string& path, LogContent& c) {
  const lcmio::UtimeOrderOptions topt = recordingTimeRule();
  lcmio::PosePlausibility popt;
  popt.max_coordinate_m = 1e300;
  popt.max_speed_mps = 1000.0;
  popt.max_yaw_rate_radps = 100.0;
  lcmio::UtimeOrder o = p.truth_order;
  if (o.admit(m.utime, topt)) {
    p.truth_order = o;  // the stray's row is remembered, as in a process
    ++c.skipped[path + ": " + channels::kGroundTruthPose + ": utime out of order or a stray jump (lcmio::UtimeOrder)"];
    return false;
  }
  lcmio::PoseStreamCheck k = o.restarts() != p.truth_order.restarts() ? lcmio::PoseStreamCheck{} : p.truth_check;
  if (k.admit(m.utime, m.x_m, m.y_m, m.theta_rad, popt)) {
    ++c.skipped[path + ": " + channels::kGroundTruthPose + ": implausible jump of the pose (lcmio::PoseStreamCheck)"];
    return false;
  }
  p.truth_order = o;
  p.truth_check = k;
  return true;
}

/// One event of the SLAM side (want_slam): SLAM_POSE, SLAM_MAP, SLAM_ASSOCIATIONS, OMNI_FEATURES.
void readSlamEvent(const std::string& path, const lcmio::LogEvent& ev, PoseMaps& p, LogContent& c) {
  if (ev.channel == channels::kSlamPose) {
    if (auto m = decodeValid<pose_t>(path, ev, c))
      keepByUtime(p.slam, m->utime, Pose2{m->x_m, m->y_m, m->theta_rad}, path, ev.channel, c);
  } else if (ev.channel == channels::kSlamAssociations) {
    if (auto m = decodeValid<associations_t>(path, ev, c))
      keepByUtime(c.associations, m->utime, m->landmark_id, path, ev.channel, c);
  } else if (ev.channel == channels::kSlamMap) {
    readMap(path, ev, true, c);
  } else if (ev.channel == channels::kSlamTrajectory) {
    auto m = decodeValid<slam_trajectory_t>(path, ev, c);
    if (m && m->ok && (!c.smoothed_utime || m->utime >= *c.smoothed_utime)) {  // the newest solve
      c.smoothed.clear();
      for (int32_t k = 0; k < m->num_keyframes; ++k)
        c.smoothed.push_back({m->keyframe_utime[k], Pose2{m->x_m[k], m->y_m[k], m->theta_rad[k]}});
      c.smoothed_utime = m->utime;
    }
  } else if (ev.channel == channels::kOmniFeatures) {
    ++c.feature_frames;
    if (auto m = decodeValid<features_t>(path, ev, c)) {
      if (admitFrame(m->utime, p, path, c)) c.frame_utimes.push_back(m->utime);
      else --c.feature_frames;
    }
  }
}

/// One event of the truth side (want_truth): GROUND_TRUTH_POSE, _MAP, _FEATURE_LABELS.
void readTruthEvent(const std::string& path, const lcmio::LogEvent& ev, PoseMaps& p, LogContent& c) {
  if (ev.channel == channels::kGroundTruthPose) {
    auto m = decodeValid<pose_t>(path, ev, c);
    if (m && admitTruth(*m, p, path, c))
      keepByUtime(p.truth, m->utime, Pose2{m->x_m, m->y_m, m->theta_rad}, path, ev.channel, c);
  } else if (ev.channel == channels::kGroundTruthFeatureLabels) {
    if (auto m = decodeValid<feature_labels_t>(path, ev, c))
      keepByUtime(c.labels, m->utime, m->landmark_id, path, ev.channel, c);
  } else if (ev.channel == channels::kGroundTruthMap) {
    readMap(path, ev, false, c);
  }
}

}  // namespace

void readLog(const std::string& path, bool want_slam, bool want_truth, LogContent& c) {
  PoseMaps p;
  const lcmio::LogReadResult got = lcmio::forEachEvent(path, [&](const lcmio::LogEvent& ev) {
    if (ev.channel == channels::kOdometry) {
      if (auto m = decodeValid<odometry_t>(path, ev, c))
        keepByUtime(p.odom, m->utime, Pose2{m->x_m, m->y_m, m->theta_rad}, path, ev.channel, c);
    } else if (want_slam && (ev.channel.rfind("SLAM_", 0) == 0 || ev.channel == channels::kOmniFeatures)) {
      readSlamEvent(path, ev, p, c);
    } else if (want_truth) {
      readTruthEvent(path, ev, p, c);
    }
  });
  if (const auto problem = got.problem(path)) {
    std::cerr << "omnislam-eval: warning: " << *problem << "\n";
    c.unreadable_bytes += got.unreadable();
  }
  if (want_slam) c.slam = posesOf(p.slam);
  if (want_truth) c.truth = posesOf(p.truth);
  if (c.odometry.empty()) c.odometry = posesOf(p.odom);
}

}  // namespace omnislam::evaltool
