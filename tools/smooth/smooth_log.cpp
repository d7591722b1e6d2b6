// Batch or incremental smoothing of a recorded SLAM run: log in, problem, core smoother, log out (smooth_log.h).
#include "smooth_log.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "omnislam/associations_t.hpp"
#include "omnislam/core/angles.h"
#include "omnislam/core/eval/metrics.h"
#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/validation.h"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/lcmio/utime_order.h"
#include "omnislam/lcmio/validate.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"

namespace omnislam::smooth {
namespace {

struct Counter {
  std::map<std::string, int64_t> n;
  std::map<std::string, lcmio::UtimeOrder> order;  ///< per channel, as lcmio::Node checks a live input
  void add(const std::string& why) { ++n[why]; }
};

/// The event decoded as Msg if it decodes and passes lcmio::validate; otherwise counted with the
/// channel and the reason.
template <class Msg>
std::optional<Msg> decodeValid(const lcmio::LogEvent& ev, Counter& bad) {
  std::string why;
  auto m = lcmio::decodeValid<Msg>(ev, &why);
  if (!m) {
    bad.add(ev.channel + ": " + why);
    return std::nullopt;
  }
  // Inputs are kept by utime: a duplicate or a step back would silently replace or re-sort one.
  // A recording's gaps are data (an odometry logger paused for 10 s), not faults to guard a live
  // filter from: a jump is more than 60 s ahead here, as before the live rule followed each
  // stream's rate (docs/lcm.md, "Time faults").
  lcmio::UtimeOrderOptions opt;
  opt.min_forward_jump_us = opt.max_forward_jump_us;
  if (bad.order[ev.channel].admit(m->utime, opt)) {
    bad.add(ev.channel + ": utime duplicated, out of order or jumping (lcmio::UtimeOrder)");
    return std::nullopt;
  }
  return m;
}

/// m[utime] = v. After a new timeline (lcmio::UtimeOrder accepts one) a utime may come again: it
/// replaces the earlier message, counted with its reason, never silently.
template <class V>
void put(std::map<int64_t, V>& m, int64_t utime, V v, const std::string& channel, Counter& bad) {
  if (!m.insert_or_assign(utime, std::move(v)).second)
    bad.add(channel + ": utime already read before its timeline restarted, replaced by this later message");
}

/// One associated azimuth: the frame (problem pose index) it was seen from.
struct Ray {
  int node;
  double azimuth_rad, sigma_rad;
  Eigen::Vector3d p_CinR_m;
};

/// Least-squares crossing of the rays from `poses`; std::nullopt when they do not cross. With
/// min_parallax_rad > 0 also when the crossing is behind one of them or they see it over less than
/// min_parallax_rad (largest minus smallest direction from the camera centres to the crossing).
std::optional<Eigen::Vector2d> crossRays(const std::vector<Pose2>& poses, const std::vector<Ray>& rays,
                                         double min_parallax_rad) {
  std::vector<Eigen::Vector2d> c;
  std::vector<double> phi;
  for (const Ray& r : rays) {
    const Pose2& x = poses[static_cast<size_t>(r.node)];
    c.push_back(slam::cameraCentreInWorld(x, r.p_CinR_m).head<2>());
    phi.push_back(x.theta_rad + r.azimuth_rad);
  }
  const auto p = slam::intersectRays2D(c, phi);
  if (!p || min_parallax_rad <= 0.0) return p;
  double lo = 0.0, hi = 0.0;
  const Eigen::Vector2d d0 = *p - c[0];
  const double ref = std::atan2(d0.y(), d0.x());
  for (size_t k = 0; k < c.size(); ++k) {
    const Eigen::Vector2d d = *p - c[k];
    if (d.dot(Eigen::Vector2d(std::cos(phi[k]), std::sin(phi[k]))) <= 0.0) return std::nullopt;
    const double a = wrapAngle(std::atan2(d.y(), d.x()) - ref);
    lo = std::min(lo, a);
    hi = std::max(hi, a);
  }
  if (hi - lo < min_parallax_rad) return std::nullopt;
  return p;
}

/// The bearing factor of `r` on landmark `landmark` (an index into the problem's landmarks).
slam::SmootherBearingFactor bearingFactor(const Ray& r, int landmark) {
  return {r.node, landmark, r.azimuth_rad, r.sigma_rad, r.p_CinR_m};
}

/// Throws with the reason unless the solve succeeded with a finite cost, poses and landmarks (the
/// core refuses an infinite initial cost; a solve can still end non-finite).
void requireSolved(const slam::SmootherResult& r) {
  if (!r.failure.empty()) throw std::invalid_argument("smoother: " + r.failure);
  bool finite = std::isfinite(r.initial_cost) && std::isfinite(r.final_cost);
  for (const Pose2& p : r.poses) finite = finite && std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad);
  for (const Eigen::Vector2d& l : r.landmarks_m) finite = finite && l.allFinite();
  if (!finite) {
    std::ostringstream o;
    o << "smoother: diverged (cost " << r.initial_cost << " -> " << r.final_cost
      << ", or a pose or landmark not finite): an input pose or landmark is too large to smooth";
    throw std::invalid_argument(o.str());
  }
}

}  // namespace

std::string SmoothLogOptions::validate() const {
  if (!incremental) return {};
  slam::detail::FieldChecker c;
  c.inClosed("min_rays", min_rays, 2, std::numeric_limits<int>::max())
      .inRightOpen("min_parallax_rad", min_parallax_rad, 0.0, M_PI);
  return c.message();
}

SmoothLogReport smoothLog(const std::string& in_log, const std::string& out_log, const SmoothLogOptions& opt) {
  if (const std::string why = opt.validate(); !why.empty()) throw std::invalid_argument(why);
  lcmio::requireDistinctFiles(in_log, out_log, "--out");
  SmoothLogReport rep;
  Counter bad;
  std::map<int64_t, Pose2> odo;
  std::map<int64_t, pose_t> slam_pose;
  std::map<int64_t, features_t> frames;
  std::map<int64_t, std::vector<int64_t>> assoc;  // from the chosen source, by frame utime
  std::map<int64_t, Eigen::Vector2d> last_map_position;
  const char* assoc_channel = opt.associations == AssociationSource::kSlam ? channels::kSlamAssociations
                                                                            : channels::kGroundTruthFeatureLabels;
  const lcmio::LogReadResult got = lcmio::forEachEvent(in_log, [&](const lcmio::LogEvent& ev) {
    const std::string& ch = ev.channel;
    if (ch == channels::kOdometry) {
      if (const auto m = decodeValid<odometry_t>(ev, bad)) put(odo, m->utime, Pose2{m->x_m, m->y_m, m->theta_rad}, ch, bad);
    } else if (ch == channels::kSlamPose) {
      if (const auto m = decodeValid<pose_t>(ev, bad)) put(slam_pose, m->utime, *m, ch, bad);
    } else if (ch == channels::kOmniFeatures) {
      if (const auto m = decodeValid<features_t>(ev, bad)) put(frames, m->utime, *m, ch, bad);
    } else if (ch == channels::kSlamMap) {
      if (const auto m = decodeValid<map_t>(ev, bad))
        for (const auto& l : m->landmarks) last_map_position[l.id] = Eigen::Vector2d(l.position_m[0], l.position_m[1]);
    } else if (ch == assoc_channel) {
      if (opt.associations == AssociationSource::kSlam) {
        if (const auto m = decodeValid<associations_t>(ev, bad)) put(assoc, m->utime, m->landmark_id, ch, bad);
      } else if (const auto m = decodeValid<feature_labels_t>(ev, bad)) {
        put(assoc, m->utime, m->landmark_id, ch, bad);
      }
    }
  });
  if (const auto problem = got.problem(in_log)) rep.problems.push_back(*problem);
  for (const auto& [why, count] : bad.n) {
    rep.skipped_messages += count;
    rep.problems.push_back(why + " (" + std::to_string(count) + ")");
  }
  bad.n.clear();  // counted; what the problem building below refuses is added at the end
  for (const auto& [channel, order] : bad.order)
    if (order.restarts() > 0)
      rep.restarts.push_back(channel + ": " + std::to_string(order.restarts()) + " new timeline(s) accepted, the last: " +
                             order.lastRestart() + "; a message at a utime already read replaces the earlier one");
  // A refusal names what was skipped: the reason a channel is short is often there.
  auto refuse = [&rep](const std::string& why) {
    std::string all = why;
    for (size_t k = 0; k < rep.problems.size(); ++k) all += (k == 0 ? " (skipped: " : "; ") + rep.problems[k];
    throw std::invalid_argument(all + (rep.problems.empty() ? "" : ")"));
  };
  if (slam_pose.empty()) refuse(in_log + ": no SLAM_POSE message");
  if (odo.size() < 2) refuse(in_log + ": fewer than two ODOMETRY messages");

  // Poses: one per SLAM_POSE, the filter's estimate as the initial value.
  slam::SmootherProblem pb;
  std::vector<int64_t> utimes;
  std::map<int64_t, int> node_of;
  for (const auto& [u, p] : slam_pose) {
    node_of[u] = static_cast<int>(utimes.size());
    utimes.push_back(u);
    pb.poses.push_back(Pose2{p.x_m, p.y_m, p.theta_rad});
  }
  // Cumulative odometry at every frame (interpolated; nothing outside the samples' span, nor across
  // a gap between samples longer than max_odometry_gap_us: the filter's pairing rule).
  std::vector<eval::TimedPose> odo_track;
  for (const auto& [u, p] : odo) odo_track.push_back({u, p});
  std::vector<std::optional<Pose2>> odo_at(utimes.size());
  for (size_t i = 0; i < utimes.size(); ++i) {
    odo_at[i] = eval::poseAt(odo_track, utimes[i], opt.max_odometry_gap_us);
    if (odo_at[i]) continue;
    ++rep.frames_without_odometry;
    if (eval::poseAt(odo_track, utimes[i], std::numeric_limits<int64_t>::max())) ++rep.frames_across_odometry_gap;
  }
  // Odometry: the filter's step between consecutive frames, with its R_t (motion_model.h).
  for (size_t i = 1; i < utimes.size(); ++i) {
    if (!odo_at[i - 1] || !odo_at[i]) continue;
    const Pose2 u = slam::odometryIncrement(*odo_at[i - 1], *odo_at[i]);
    pb.odometry.push_back({static_cast<int>(i - 1), static_cast<int>(i), u, slam::incrementCovariance(u, opt.motion)});
  }
  if (opt.initial_from_odometry) {
    if (!odo_at[0]) refuse(in_log + ": the first SLAM_POSE has no ODOMETRY around it (outside its span or in a gap)");
    for (size_t i = 1; i < utimes.size(); ++i)
      if (odo_at[i]) pb.poses[i] = pb.poses[0].compose(odo_at[0]->between(*odo_at[i]));
  }
  // Bearings of associated vertical-line features, in frame order, with their landmark id.
  std::vector<std::pair<int64_t, Ray>> rays;
  for (const auto& [u, f] : frames) {
    const auto n = node_of.find(u);
    const auto a = assoc.find(u);
    if (n == node_of.end() || a == assoc.end()) continue;  // a frame the filter did not answer
    if (a->second.size() != f.features.size()) {
      bad.add("association and OMNI_FEATURES of one frame differ in length");
      continue;
    }
    const Eigen::Vector3d p_CinR(f.camera_position_m[0], f.camera_position_m[1], f.camera_position_m[2]);
    for (size_t k = 0; k < f.features.size(); ++k) {
      const feature_t& ft = f.features[k];
      if (a->second[k] < 0 || ft.kind != feature_t::KIND_VERTICAL_LINE) continue;
      // lcmio::validate has checked the azimuth, its variance (> 0) and the camera position.
      rays.push_back({a->second[k], {n->second, ft.azimuth_rad, std::sqrt(ft.covariance[0][0]), p_CinR}});
    }
  }
  std::vector<int64_t> landmark_ids;
  std::vector<Pose2> published;  // SLAM_POSE of the copy, by node
  if (!opt.incremental) {
    std::map<int64_t, std::vector<Ray>> by_id;
    for (const auto& [id, r] : rays) by_id[id].push_back(r);
    for (const auto& [id, rs] : by_id) {
      std::optional<Eigen::Vector2d> init;
      const auto known = last_map_position.find(id);
      if (opt.associations == AssociationSource::kSlam && known != last_map_position.end())
        init = known->second;
      else  // cross the rays from the initial poses
        init = crossRays(pb.poses, rs, 0.0);
      if (!init) {
        ++rep.unanchored_landmarks;
        continue;
      }
      const int j = static_cast<int>(pb.landmarks_m.size());
      pb.landmarks_m.push_back(*init);
      landmark_ids.push_back(id);
      for (const Ray& r : rs) pb.bearings.push_back(bearingFactor(r, j));
    }
    rep.result = slam::smoothBearingOnly(pb, opt.smoother);
    requireSolved(rep.result);
    rep.solves = 1;
    published = rep.result.poses;
  } else {
    // Frame by frame: pb.odometry holds, in order, the step into every frame (checked here).
    if (rep.frames_without_odometry > 0 || pb.odometry.size() + 1 != utimes.size()) {
      std::ostringstream o;
      o << in_log << ": --incremental needs ODOMETRY over every frame; " << rep.frames_without_odometry
        << " frame(s) without (" << rep.frames_across_odometry_gap << " of them across a gap over "
        << opt.max_odometry_gap_us / 1e6 << " s)";
      refuse(o.str());
    }
    slam::SmootherProblem grown;
    std::map<int64_t, int> landmark_of;
    std::map<int64_t, std::vector<Ray>> pending;
    size_t next = 0;
    const auto start = std::chrono::steady_clock::now();
    auto last_report = start;
    size_t next_tenth = 1;
    for (size_t i = 0; i < utimes.size(); ++i) {
      if (opt.progress && i > 0) {  // quadratic in the frames: say how far it is
        const auto now = std::chrono::steady_clock::now();
        if (i * 10 >= next_tenth * utimes.size() || now - last_report >= std::chrono::seconds(30)) {
          while (i * 10 >= next_tenth * utimes.size()) ++next_tenth;
          last_report = now;
          std::ostringstream o;
          o << "incremental: frame " << i << " of " << utimes.size() << " (" << (100 * i / utimes.size()) << " %), "
            << std::chrono::duration_cast<std::chrono::seconds>(now - start).count() << " s; the last solve: "
            << grown.poses.size() << " poses, " << grown.landmarks_m.size() << " landmarks";
          opt.progress(o.str());
        }
      }
      if (i == 0) {
        grown.poses.push_back(pb.poses[0]);
      } else {
        const slam::SmootherOdometryFactor& step = pb.odometry[i - 1];
        grown.poses.push_back(grown.poses.back().compose(step.increment));
        grown.odometry.push_back(step);
      }
      for (; next < rays.size() && rays[next].second.node == static_cast<int>(i); ++next) {
        const auto& [id, r] = rays[next];
        const auto lm = landmark_of.find(id);
        if (lm != landmark_of.end()) {
          grown.bearings.push_back(bearingFactor(r, lm->second));
          continue;
        }
        std::vector<Ray>& rs = pending[id];
        rs.push_back(r);
        if (static_cast<int>(rs.size()) < opt.min_rays) continue;
        const auto p = crossRays(grown.poses, rs, opt.min_parallax_rad);
        if (!p) continue;
        const int j = static_cast<int>(grown.landmarks_m.size());
        grown.landmarks_m.push_back(*p);
        landmark_ids.push_back(id);
        landmark_of[id] = j;
        for (const Ray& q : rs) grown.bearings.push_back(bearingFactor(q, j));
        pending.erase(id);
      }
      rep.result = slam::smoothBearingOnly(grown, opt.smoother);
      requireSolved(rep.result);
      ++rep.solves;
      grown.poses = rep.result.poses;
      grown.landmarks_m = rep.result.landmarks_m;
      published.push_back(grown.poses.back());
    }
    rep.unanchored_landmarks = static_cast<int64_t>(pending.size());
    pb = std::move(grown);
  }
  rep.poses = static_cast<int64_t>(pb.poses.size());
  rep.odometry_factors = static_cast<int64_t>(pb.odometry.size());
  rep.bearing_factors = static_cast<int64_t>(pb.bearings.size());
  rep.landmarks = static_cast<int64_t>(pb.landmarks_m.size());
  std::vector<int32_t> inliers(pb.landmarks_m.size(), 0);
  for (size_t k = 0; k < pb.bearings.size(); ++k) {
    if (rep.result.bearing_weights[k] < 0.5)
      ++rep.bearings_downweighted;
    else
      ++inliers[static_cast<size_t>(pb.bearings[k].landmark)];
  }
  for (const auto& [why, count] : bad.n) {
    rep.skipped_messages += count;
    rep.problems.push_back(why + " (" + std::to_string(count) + ")");
  }

  // The copy: smoothed SLAM_POSE in place, one final SLAM_MAP at the end.
  // Atomic: a run stopped part-way leaves OUT.partial, never a short OUT that reads as complete.
  lcmio::LogWriter out(out_log, lcmio::LogWriter::Mode::kAtomic);
  int64_t last_timestamp = 0;
  lcmio::forEachEvent(in_log, [&](const lcmio::LogEvent& ev) {
    last_timestamp = ev.log_utime;
    const std::string& ch = ev.channel;
    if (ch == channels::kSlamMap || ch == channels::kSlamParticles) return;
    if (ch == channels::kSlamAssociations && opt.associations != AssociationSource::kSlam) return;
    if (ch == channels::kSlamPose) {
      auto m = lcmio::decodeAs<pose_t>(ev);
      if (!m) return;
      const auto n = node_of.find(m->utime);
      if (n == node_of.end()) return;  // non-finite: skipped above
      const Pose2& p = published[static_cast<size_t>(n->second)];
      m->x_m = p.x_m, m->y_m = p.y_m, m->theta_rad = p.theta_rad;
      out.write(ev.log_utime, ch, *m);
      return;
    }
    out.write(ev.log_utime, ch, ev.data.data(), static_cast<int32_t>(ev.data.size()));
  });
  map_t map{};
  map.utime = utimes.back();
  map.seq = 0;
  map.input_seq = -1;
  for (size_t j = 0; j < landmark_ids.size(); ++j) {
    landmark_t l{};
    l.id = landmark_ids[j];
    l.position_m[0] = rep.result.landmarks_m[j].x();
    l.position_m[1] = rep.result.landmarks_m[j].y();
    l.type = 1;
    l.times_detected = inliers[j];
    l.kind = feature_t::KIND_VERTICAL_LINE;
    map.landmarks.push_back(l);
  }
  map.num_landmarks = static_cast<int32_t>(map.landmarks.size());
  map.num_candidates = 0;
  out.write(last_timestamp, channels::kSlamMap, map);
  out.commit();
  return rep;
}

}  // namespace omnislam::smooth
