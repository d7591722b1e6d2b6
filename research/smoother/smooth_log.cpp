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
#include "omnislam/eval/metrics.h"
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
  // stream's rate (docs/user/lcm.md, "Time faults").
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
  for (const Pose2& p : r.poses)
    finite = finite && std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad);
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

namespace {

// What smoothing uses of the recorded run, by utime.
struct Inputs {
  std::map<int64_t, Pose2> odo;
  std::map<int64_t, pose_t> slam_pose;
  std::map<int64_t, features_t> frames;
  std::map<int64_t, std::vector<int64_t>> assoc;  ///< from the chosen source, by frame utime
  std::map<int64_t, Eigen::Vector2d> last_map_position;
};

// A refusal names what was skipped: the reason a channel is short is often there.
[[noreturn]] void refuse(const SmoothLogReport& rep, const std::string& why) {
  std::string all = why;
  for (size_t k = 0; k < rep.problems.size(); ++k) all += (k == 0 ? " (skipped: " : "; ") + rep.problems[k];
  throw std::invalid_argument(all + (rep.problems.empty() ? "" : ")"));
}

// Moves the counts of skipped messages into the report's problems.
void reportSkipped(Counter& bad, SmoothLogReport& rep) {
  for (const auto& [why, count] : bad.n) {
    rep.skipped_messages += count;
    rep.problems.push_back(why + " (" + std::to_string(count) + ")");
  }
  bad.n.clear();
}

Inputs readInputs(const std::string& in_log, const SmoothLogOptions& opt, Counter& bad, SmoothLogReport& rep) {
  Inputs in;
  const char* assoc_channel =
      opt.associations == AssociationSource::kSlam ? channels::kSlamAssociations : channels::kGroundTruthFeatureLabels;
  const lcmio::LogReadResult got = lcmio::forEachEvent(in_log, [&](const lcmio::LogEvent& ev) {
    const std::string& ch = ev.channel;
    if (ch == channels::kOdometry) {
      if (const auto m = decodeValid<odometry_t>(ev, bad))
        put(in.odo, m->utime, Pose2{m->x_m, m->y_m, m->theta_rad}, ch, bad);
    } else if (ch == channels::kSlamPose) {
      if (const auto m = decodeValid<pose_t>(ev, bad)) put(in.slam_pose, m->utime, *m, ch, bad);
    } else if (ch == channels::kOmniFeatures) {
      if (const auto m = decodeValid<features_t>(ev, bad)) put(in.frames, m->utime, *m, ch, bad);
    } else if (ch == channels::kSlamMap) {
      if (const auto m = decodeValid<map_t>(ev, bad))
        for (const auto& l : m->landmarks)
          in.last_map_position[l.id] = Eigen::Vector2d(l.position_m[0], l.position_m[1]);
    } else if (ch == assoc_channel) {
      if (opt.associations == AssociationSource::kSlam) {
        if (const auto m = decodeValid<associations_t>(ev, bad)) put(in.assoc, m->utime, m->landmark_id, ch, bad);
      } else if (const auto m = decodeValid<feature_labels_t>(ev, bad)) {
        put(in.assoc, m->utime, m->landmark_id, ch, bad);
      }
    }
  });
  if (const auto problem = got.problem(in_log)) rep.problems.push_back(*problem);
  reportSkipped(bad, rep);  // what the problem building below refuses is added at the end
  for (const auto& [channel, order] : bad.order)
    if (order.restarts() > 0)
      rep.restarts.push_back(channel + ": " + std::to_string(order.restarts()) +
                             " new timeline(s) accepted, the last: " + order.lastRestart() +
                             "; a message at a utime already read replaces the earlier one");
  if (in.slam_pose.empty()) refuse(rep, in_log + ": no SLAM_POSE message");
  if (in.odo.size() < 2) refuse(rep, in_log + ": fewer than two ODOMETRY messages");
  return in;
}

// The poses of the problem (one per SLAM_POSE) with their odometry factors.
struct Graph {
  slam::SmootherProblem pb;
  std::vector<int64_t> utimes;     ///< of the nodes
  std::map<int64_t, int> node_of;  ///< by utime
};

Graph buildPoses(const Inputs& in, const std::string& in_log, const SmoothLogOptions& opt, SmoothLogReport& rep) {
  Graph gr;
  // Poses: one per SLAM_POSE, the filter's estimate as the initial value.
  for (const auto& [u, p] : in.slam_pose) {
    gr.node_of[u] = static_cast<int>(gr.utimes.size());
    gr.utimes.push_back(u);
    gr.pb.poses.push_back(Pose2{p.x_m, p.y_m, p.theta_rad});
  }
  // Cumulative odometry at every frame (interpolated; nothing outside the samples' span, nor across
  // a gap between samples longer than max_odometry_gap_us: the filter's pairing rule).
  std::vector<eval::TimedPose> odo_track;
  for (const auto& [u, p] : in.odo) odo_track.push_back({u, p});
  std::vector<std::optional<Pose2>> odo_at(gr.utimes.size());
  for (size_t i = 0; i < gr.utimes.size(); ++i) {
    odo_at[i] = eval::poseAt(odo_track, gr.utimes[i], opt.max_odometry_gap_us);
    if (odo_at[i]) continue;
    ++rep.frames_without_odometry;
    if (eval::poseAt(odo_track, gr.utimes[i], std::numeric_limits<int64_t>::max())) ++rep.frames_across_odometry_gap;
  }
  // Odometry: the filter's step between consecutive frames, with its R_t (motion_model.h).
  for (size_t i = 1; i < gr.utimes.size(); ++i) {
    if (!odo_at[i - 1] || !odo_at[i]) continue;
    const Pose2 u = slam::odometryIncrement(*odo_at[i - 1], *odo_at[i]);
    gr.pb.odometry.push_back(
        {static_cast<int>(i - 1), static_cast<int>(i), u, slam::incrementCovariance(u, opt.motion)});
  }
  if (opt.initial_from_odometry) {
    if (!odo_at[0])
      refuse(rep, in_log + ": the first SLAM_POSE has no ODOMETRY around it (outside its span or in a gap)");
    for (size_t i = 1; i < gr.utimes.size(); ++i)
      if (odo_at[i]) gr.pb.poses[i] = gr.pb.poses[0].compose(odo_at[0]->between(*odo_at[i]));
  }
  return gr;
}

// Bearings of associated vertical-line features, in frame order, with their landmark id.
std::vector<std::pair<int64_t, Ray>> collectRays(const Inputs& in, const std::map<int64_t, int>& node_of,
                                                 Counter& bad) {
  std::vector<std::pair<int64_t, Ray>> rays;
  for (const auto& [u, f] : in.frames) {
    const auto n = node_of.find(u);
    const auto a = in.assoc.find(u);
    if (n == node_of.end() || a == in.assoc.end()) continue;  // a frame the filter did not answer
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
  return rays;
}

// Batch: every landmark from the last SLAM_MAP (or its rays crossed), one solve. Returns the
// smoothed pose of every node.
std::vector<Pose2> solveBatch(const Inputs& in, const std::vector<std::pair<int64_t, Ray>>& rays,
                              const SmoothLogOptions& opt, Graph& gr, std::vector<int64_t>& landmark_ids,
                              SmoothLogReport& rep) {
  std::map<int64_t, std::vector<Ray>> by_id;
  for (const auto& [id, r] : rays) by_id[id].push_back(r);
  for (const auto& [id, rs] : by_id) {
    std::optional<Eigen::Vector2d> init;
    const auto known = in.last_map_position.find(id);
    if (opt.associations == AssociationSource::kSlam && known != in.last_map_position.end()) init = known->second;
    else  // cross the rays from the initial poses
      init = crossRays(gr.pb.poses, rs, 0.0);
    if (!init) {
      ++rep.unanchored_landmarks;
      continue;
    }
    const int j = static_cast<int>(gr.pb.landmarks_m.size());
    gr.pb.landmarks_m.push_back(*init);
    landmark_ids.push_back(id);
    for (const Ray& r : rs) gr.pb.bearings.push_back(bearingFactor(r, j));
  }
  rep.result = slam::smoothBearingOnly(gr.pb, opt.smoother);
  requireSolved(rep.result);
  rep.solves = 1;
  return rep.result.poses;
}

// --incremental progress: a line every 10 % of the frames and at least every 30 s.
class Progress {
 public:
  explicit Progress(const SmoothLogOptions& opt) : opt_(opt) {}
  void maybeReport(size_t i, size_t frames, const slam::SmootherProblem& grown) {
    if (!opt_.progress || i == 0) return;  // quadratic in the frames: say how far it is
    const auto now = std::chrono::steady_clock::now();
    if (i * 10 < next_tenth_ * frames && now - last_report_ < std::chrono::seconds(30)) return;
    while (i * 10 >= next_tenth_ * frames) ++next_tenth_;
    last_report_ = now;
    std::ostringstream o;
    o << "incremental: frame " << i << " of " << frames << " (" << (100 * i / frames) << " %), "
      << std::chrono::duration_cast<std::chrono::seconds>(now - start_).count()
      << " s; the last solve: " << grown.poses.size() << " poses, " << grown.landmarks_m.size() << " landmarks";
    opt_.progress(o.str());
  }

 private:
  const SmoothLogOptions& opt_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_report_ = start_;
  size_t next_tenth_ = 1;
};

// The landmarks of the rays seen at node i, added to `grown`: a known landmark gets the bearing, a
// new one is anchored once min_rays rays cross with min_parallax_rad.
struct LandmarkGrowth {
  std::map<int64_t, int> landmark_of;
  std::map<int64_t, std::vector<Ray>> pending;
  size_t next = 0;  ///< the next ray to take
  void add(const std::vector<std::pair<int64_t, Ray>>& rays, size_t i, const SmoothLogOptions& opt,
           slam::SmootherProblem& grown, std::vector<int64_t>& landmark_ids) {
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
  }
};

// Frame by frame: the problem grown by one pose and its rays, solved at every frame; the pose
// published for a frame is the one solved then (causal). gr.pb becomes the grown problem.
std::vector<Pose2> solveIncremental(const std::vector<std::pair<int64_t, Ray>>& rays, const std::string& in_log,
                                    const SmoothLogOptions& opt, Graph& gr, std::vector<int64_t>& landmark_ids,
                                    SmoothLogReport& rep) {
  // pb.odometry must hold, in order, the step into every frame (checked here).
  if (rep.frames_without_odometry > 0 || gr.pb.odometry.size() + 1 != gr.utimes.size()) {
    std::ostringstream o;
    o << in_log << ": --incremental needs ODOMETRY over every frame; " << rep.frames_without_odometry
      << " frame(s) without (" << rep.frames_across_odometry_gap << " of them across a gap over "
      << opt.max_odometry_gap_us / 1e6 << " s)";
    refuse(rep, o.str());
  }
  slam::SmootherProblem grown;
  LandmarkGrowth growth;
  Progress progress(opt);
  std::vector<Pose2> published;
  for (size_t i = 0; i < gr.utimes.size(); ++i) {
    progress.maybeReport(i, gr.utimes.size(), grown);
    if (i == 0) {
      grown.poses.push_back(gr.pb.poses[0]);
    } else {
      const slam::SmootherOdometryFactor& step = gr.pb.odometry[i - 1];
      grown.poses.push_back(grown.poses.back().compose(step.increment));
      grown.odometry.push_back(step);
    }
    growth.add(rays, i, opt, grown, landmark_ids);
    rep.result = slam::smoothBearingOnly(grown, opt.smoother);
    requireSolved(rep.result);
    ++rep.solves;
    grown.poses = rep.result.poses;
    grown.landmarks_m = rep.result.landmarks_m;
    published.push_back(grown.poses.back());
  }
  rep.unanchored_landmarks = static_cast<int64_t>(growth.pending.size());
  gr.pb = std::move(grown);
  return published;
}

// Problem sizes and down-weighted bearings into the report; the inlier bearings per landmark.
std::vector<int32_t> summarise(const slam::SmootherProblem& pb, Counter& bad, SmoothLogReport& rep) {
  rep.poses = static_cast<int64_t>(pb.poses.size());
  rep.odometry_factors = static_cast<int64_t>(pb.odometry.size());
  rep.bearing_factors = static_cast<int64_t>(pb.bearings.size());
  rep.landmarks = static_cast<int64_t>(pb.landmarks_m.size());
  std::vector<int32_t> inliers(pb.landmarks_m.size(), 0);
  for (size_t k = 0; k < pb.bearings.size(); ++k) {
    if (rep.result.bearing_weights[k] < 0.5) ++rep.bearings_downweighted;
    else ++inliers[static_cast<size_t>(pb.bearings[k].landmark)];
  }
  reportSkipped(bad, rep);
  return inliers;
}

// The final SLAM_MAP: the smoothed landmarks, each with its inlier bearings as times_detected.
map_t smoothedMap(int64_t utime, const std::vector<int64_t>& landmark_ids, const std::vector<int32_t>& inliers,
                  const SmoothLogReport& rep) {
  map_t map{};
  map.utime = utime;
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
  return map;
}

// The copy: smoothed SLAM_POSE in place, one final SLAM_MAP at the end. Atomic: a run stopped
// part-way leaves OUT.partial, never a short OUT that reads as complete.
void writeCopy(const std::string& in_log, const std::string& out_log, const SmoothLogOptions& opt, const Graph& gr,
               const std::vector<Pose2>& published, const map_t& map) {
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
      const auto n = gr.node_of.find(m->utime);
      if (n == gr.node_of.end()) return;  // non-finite: skipped above
      const Pose2& p = published[static_cast<size_t>(n->second)];
      m->x_m = p.x_m, m->y_m = p.y_m, m->theta_rad = p.theta_rad;
      out.write(ev.log_utime, ch, *m);
      return;
    }
    out.write(ev.log_utime, ch, ev.data.data(), static_cast<int32_t>(ev.data.size()));
  });
  out.write(last_timestamp, channels::kSlamMap, map);
  out.commit();
}

}  // namespace

SmoothLogReport smoothLog(const std::string& in_log, const std::string& out_log, const SmoothLogOptions& opt) {
  if (const std::string why = opt.validate(); !why.empty()) throw std::invalid_argument(why);
  lcmio::requireDistinctFiles(in_log, out_log, "--out");
  SmoothLogReport rep;
  Counter bad;
  const Inputs in = readInputs(in_log, opt, bad, rep);
  Graph gr = buildPoses(in, in_log, opt, rep);
  const auto rays = collectRays(in, gr.node_of, bad);
  std::vector<int64_t> landmark_ids;
  const std::vector<Pose2> published = opt.incremental ? solveIncremental(rays, in_log, opt, gr, landmark_ids, rep)
                                                       : solveBatch(in, rays, opt, gr, landmark_ids, rep);
  const std::vector<int32_t> inliers = summarise(gr.pb, bad, rep);
  writeCopy(in_log, out_log, opt, gr, published, smoothedMap(gr.utimes.back(), landmark_ids, inliers, rep));
  return rep;
}

}  // namespace omnislam::smooth
