// omnislam-eval: compares SLAM_POSE / SLAM_MAP of a log with GROUND_TRUTH_POSE / GROUND_TRUTH_MAP
// (from the same log or --truth) and prints a table, or one JSON object with --json. Landmarks are
// matched one-to-one by optimal assignment within --gate; unmatched estimates are spurious. No
// alignment unless --align (best rigid 2D transform of the trajectory onto the truth, applied to
// trajectory and map). Writes the SLAM, truth and (with ODOMETRY) dead-reckoning trajectories in TUM
// format for evo. Also: dead reckoning (ODOMETRY mapped into the truth frame by the start pose) raw
// and aligned, and, when the log has SLAM_ASSOCIATIONS and GROUND_TRUTH_FEATURE_LABELS, association
// precision / recall.
#include <CLI/CLI.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include "omnislam/core/eval/metrics.h"
#include "omnislam/associations_t.hpp"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/plausibility.h"
#include "omnislam/lcmio/utime_order.h"
#include "omnislam/lcmio/validate.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/vision/plots.h"

#include <opencv2/imgcodecs.hpp>

using namespace omnislam;

namespace {

struct LogContent {
  std::vector<eval::TimedPose> slam, truth;
  std::vector<Eigen::Vector3d> slam_map, truth_map;
  std::vector<Eigen::Matrix2d> slam_map_cov_xy;
  int64_t feature_frames = 0;
  bool have_slam_map = false, have_truth_map = false;
  std::optional<int64_t> slam_map_utime, truth_map_utime;  ///< of the maps kept: the newest
  std::vector<int64_t> slam_map_ids, truth_map_ids;
  std::vector<eval::TimedPose> odometry;                     ///< ODOMETRY (of the first log that has it)
  std::map<int64_t, std::vector<int64_t>> associations;      ///< SLAM_ASSOCIATIONS by frame utime
  std::map<int64_t, std::vector<int64_t>> labels;            ///< GROUND_TRUTH_FEATURE_LABELS by frame utime
  std::map<std::string, int64_t> skipped;  ///< "LOG: CHANNEL: reason" -> messages left out (undecodable, invalid)
  int64_t unreadable_bytes = 0;             ///< a truncated or corrupt tail of the log(s), not read
  int64_t skippedTotal() const {
    int64_t n = 0;
    for (const auto& [why, count] : skipped) n += count;
    return n;
  }
};

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
  if (newest && utime == *newest) ++c.skipped[path + ": " + channel + ": utime already read, replaced by this later message"];
  newest = utime;
  return true;
}

/// Poses by utime (a later message with the same utime replaces the earlier one), sorted.
std::vector<eval::TimedPose> posesOf(const std::map<int64_t, Pose2>& m) {
  std::vector<eval::TimedPose> out;
  for (const auto& [u, p] : m) out.push_back({u, p});
  return out;
}

/// The truth is judged as the processes judge it (docs/lcm.md "Time faults", docs/messages.md
/// "Plausibility"), with bounds for any dataset: a stray stamp (a copy 30 s back would replace the
/// truth of another time) or a pose that jumps faster than 1000 m/s or 100 rad/s (x = 1e300) is
/// left out and counted in c.skipped, never scored against; a refused pose leaves the time order as
/// it was. The time threshold is the fixed 60 s of a recording (a gap in it is data); the
/// coordinates are not bounded (a car's UTM coordinates are 1e5 m and more).
bool admitTruth(const pose_t& m, lcmio::UtimeOrder& order, lcmio::PoseStreamCheck& check, const std::string& path,
                LogContent& c) {
  lcmio::UtimeOrderOptions topt;
  topt.min_forward_jump_us = topt.max_forward_jump_us;
  lcmio::PosePlausibility popt;
  popt.max_coordinate_m = 1e300;
  popt.max_speed_mps = 1000.0;
  popt.max_yaw_rate_radps = 100.0;
  lcmio::UtimeOrder o = order;
  if (o.admit(m.utime, topt)) {
    order = o;  // the stray's row is remembered, as in a process
    ++c.skipped[path + ": " + channels::kGroundTruthPose + ": utime out of order or a stray jump (lcmio::UtimeOrder)"];
    return false;
  }
  lcmio::PoseStreamCheck k = o.restarts() != order.restarts() ? lcmio::PoseStreamCheck{} : check;
  if (k.admit(m.utime, m.x_m, m.y_m, m.theta_rad, popt)) {
    ++c.skipped[path + ": " + channels::kGroundTruthPose + ": implausible jump of the pose (lcmio::PoseStreamCheck)"];
    return false;
  }
  order = o;
  check = k;
  return true;
}

void read(const std::string& path, bool want_slam, bool want_truth, LogContent& c) {
  std::map<int64_t, Pose2> slam, truth, odom;
  lcmio::UtimeOrder truth_order;
  lcmio::PoseStreamCheck truth_check;
  const lcmio::LogReadResult got = lcmio::forEachEvent(path, [&](const lcmio::LogEvent& ev) {
    if (ev.channel == channels::kOdometry) {
      if (auto m = decodeValid<odometry_t>(path, ev, c))
        keepByUtime(odom, m->utime, Pose2{m->x_m, m->y_m, m->theta_rad}, path, ev.channel, c);
      return;
    }
    if (want_slam && ev.channel == channels::kSlamAssociations) {
      if (auto m = decodeValid<associations_t>(path, ev, c)) keepByUtime(c.associations, m->utime, m->landmark_id, path, ev.channel, c);
      return;
    }
    if (want_truth && ev.channel == channels::kGroundTruthFeatureLabels) {
      if (auto m = decodeValid<feature_labels_t>(path, ev, c)) keepByUtime(c.labels, m->utime, m->landmark_id, path, ev.channel, c);
      return;
    }
    if (want_slam && ev.channel == channels::kSlamPose) {
      if (auto m = decodeValid<pose_t>(path, ev, c)) keepByUtime(slam, m->utime, Pose2{m->x_m, m->y_m, m->theta_rad}, path, ev.channel, c);
    } else if (want_truth && ev.channel == channels::kGroundTruthPose) {
      auto m = decodeValid<pose_t>(path, ev, c);
      if (m && admitTruth(*m, truth_order, truth_check, path, c))
        keepByUtime(truth, m->utime, Pose2{m->x_m, m->y_m, m->theta_rad}, path, ev.channel, c);
    } else if (want_slam && ev.channel == channels::kSlamMap) {
      auto m = decodeValid<map_t>(path, ev, c);
      if (m && newestMap(c.slam_map_utime, m->utime, path, ev.channel, c)) {
        c.slam_map.clear();
        c.slam_map_cov_xy.clear();
        c.slam_map_ids.clear();
        for (const auto& l : m->landmarks) {
          c.slam_map_ids.push_back(l.id);
          c.slam_map.emplace_back(l.position_m[0], l.position_m[1], l.position_m[2]);
          Eigen::Matrix2d cov;
          cov << l.covariance[0][0], l.covariance[0][1], l.covariance[1][0], l.covariance[1][1];
          c.slam_map_cov_xy.push_back(cov);
        }
        c.have_slam_map = true;
      }
    } else if (want_truth && ev.channel == channels::kGroundTruthMap) {
      auto m = decodeValid<map_t>(path, ev, c);
      if (m && newestMap(c.truth_map_utime, m->utime, path, ev.channel, c)) {
        c.truth_map.clear();
        c.truth_map_ids.clear();
        for (const auto& l : m->landmarks) {
          c.truth_map.emplace_back(l.position_m[0], l.position_m[1], l.position_m[2]);
          c.truth_map_ids.push_back(l.id);
        }
        c.have_truth_map = true;
      }
    } else if (want_slam && ev.channel == channels::kOmniFeatures) {
      ++c.feature_frames;
    }
  });
  if (const auto problem = got.problem(path)) {
    std::cerr << "omnislam-eval: warning: " << *problem << "\n";
    c.unreadable_bytes += got.unreadable();
  }
  if (want_slam) c.slam = posesOf(slam);
  if (want_truth) c.truth = posesOf(truth);
  if (c.odometry.empty()) c.odometry = posesOf(odom);
}

/// Dead reckoning: ODOMETRY at the SLAM poses' utimes, mapped into the truth frame by the start pose
/// (the truth at the first SLAM pose, where the filter was given its start), raw and aligned.
struct DeadReckoning {
  bool available = false;
  eval::TrajectoryErrors raw, aligned;
  std::vector<eval::TimedPose> poses;  ///< odometry in the truth frame at the SLAM poses' utimes (raw)
};

DeadReckoning deadReckoning(const LogContent& c) {
  DeadReckoning d;
  constexpr int64_t kMaxOdometryGapUs = 2'000'000;  // odometry loggers may pause (MRCLAM: 1 s)
  if (c.odometry.empty() || c.slam.empty()) return d;
  const int64_t t0 = c.slam.front().utime;
  const auto odom0 = eval::poseAt(c.odometry, t0, kMaxOdometryGapUs);
  const auto truth0 = eval::poseAt(c.truth, t0, 200'000);
  if (!odom0 || !truth0) return d;
  const eval::Rigid2D T0 = eval::rigidFromPoses(*odom0, *truth0);
  std::vector<eval::TimedPose> dr;
  for (const auto& p : c.slam)
    if (auto o = eval::poseAt(c.odometry, p.utime, kMaxOdometryGapUs)) dr.push_back({p.utime, T0.apply(*o)});
  auto pairs = eval::pairByTime(dr, c.truth);
  if (pairs.empty()) return d;
  d.poses = std::move(dr);
  d.available = true;
  d.raw = eval::trajectoryErrors(pairs);
  std::vector<Eigen::Vector2d> from, to;
  for (const auto& p : pairs) {
    from.emplace_back(p.estimate.x_m, p.estimate.y_m);
    to.emplace_back(p.truth.x_m, p.truth.y_m);
  }
  if (const auto T = eval::fitRigid2D(from, to))
    for (auto& p : pairs) p.estimate = T->apply(p.estimate);
  d.aligned = eval::trajectoryErrors(pairs);
  return d;
}

/// A ratio for the table: "n/a" when its denominator is 0 (nothing to score), never a 0.
std::string ratioText(double ratio, int64_t denominator) {
  if (denominator == 0) return "n/a";
  std::ostringstream o;
  o << std::setprecision(6) << ratio;
  return o.str();
}

void writeTum(const std::string& path, const std::vector<eval::TimedPose>& poses) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write '" + path + "'");
  f << "# timestamp_s x_m y_m z_m qx qy qz qw\n" << std::setprecision(17);
  for (const auto& p : poses)
    f << p.utime * 1e-6 << " " << p.pose.x_m << " " << p.pose.y_m << " 0 0 0 " << std::sin(0.5 * p.pose.theta_rad)
      << " " << std::cos(0.5 * p.pose.theta_rad) << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-eval: SLAM estimate vs ground truth (ATE, heading, landmark errors)"};
  std::string log, truth_log, tum_prefix, plot_prefix;
  bool json = false, align = false, no_tum = false, planar = false;
  double gate_m = 2.0;
  cli.add_option("log", log, "log with SLAM_POSE and SLAM_MAP")->required()->check(CLI::ExistingFile);
  cli.add_option("--truth", truth_log, "log with GROUND_TRUTH_POSE and GROUND_TRUTH_MAP (default: the same log)")
      ->check(CLI::ExistingFile);
  cli.add_flag("--json", json, "print one JSON object instead of a table");
  cli.add_flag("--align", align, "fit the best rigid 2D transform of the trajectory onto the truth first");
  cli.add_option("--gate", gate_m, "landmark matching gate, metres")->check(omnislam::app::FiniteRange(0.01, 100.0));
  cli.add_flag("--planar", planar, "landmark distances in x, y only (2D landmarks)");
  cli.add_option("--tum-out", tum_prefix,
                 "prefix of the TUM trajectory files PREFIX.slam.tum, .truth.tum and .odometry.tum (dead reckoning "
                 "in the truth frame; default: the log's path)");
  cli.add_flag("--no-tum", no_tum, "do not write TUM files");
  cli.add_option("--plot", plot_prefix, "write PREFIX.map.png (map and trajectories) and PREFIX.errors.png");
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  return app::runMain("omnislam-eval", [&]() -> int {
    LogContent c;
    if (truth_log.empty()) {
      read(log, true, true, c);
    } else {
      read(log, true, false, c);
      read(truth_log, false, true, c);
    }
    for (const auto& [why, count] : c.skipped)
      std::cerr << "omnislam-eval: skipped " << count << " message" << (count == 1 ? "" : "s") << " of " << why << "\n";
    if (c.slam.empty()) throw std::invalid_argument(log + ": no SLAM_POSE message");
    if (c.truth.empty()) throw std::invalid_argument((truth_log.empty() ? log : truth_log) + ": no GROUND_TRUTH_POSE message");
    auto pairs = eval::pairByTime(c.slam, c.truth);
    // No pair means nothing was compared: a 0 ATE would read as a perfect run.
    if (pairs.empty())
      throw std::invalid_argument(
          "no SLAM_POSE could be compared: none of the " + std::to_string(c.slam.size()) + " poses (utime " +
          std::to_string(c.slam.front().utime) + ".." + std::to_string(c.slam.back().utime) +
          ") lies between two GROUND_TRUTH_POSE at most 0.2 s apart (truth utime " + std::to_string(c.truth.front().utime) +
          ".." + std::to_string(c.truth.back().utime) + ")");
    std::optional<eval::Rigid2D> T;
    if (align) {
      std::vector<Eigen::Vector2d> from, to;
      for (const auto& p : pairs) {
        from.emplace_back(p.estimate.x_m, p.estimate.y_m);
        to.emplace_back(p.truth.x_m, p.truth.y_m);
      }
      if (const std::string why = eval::rigidFitProblem(from, to); !why.empty())
        throw std::invalid_argument("--align: " + why);
      T = eval::fitRigid2D(from, to);
      if (!T) throw std::invalid_argument("--align: the fitted transform is degenerate or not finite");
      for (auto& p : pairs) p.estimate = T->apply(p.estimate);
      for (auto& l : c.slam_map) l = T->apply(l);
      for (auto& p : c.slam) p.pose = T->apply(p.pose);
    }
    const auto te = eval::trajectoryErrors(pairs);
    const auto me = [&] {
      try {
        return eval::mapErrors(c.slam_map, c.truth_map, gate_m, planar);
      } catch (const std::invalid_argument& e) {  // a group too large to solve: name the flag
        std::ostringstream o;
        o << e.what() << " (--gate " << gate_m << " m)";
        throw std::invalid_argument(o.str());
      }
    }();
    const int64_t frames = c.feature_frames > 0 ? c.feature_frames : static_cast<int64_t>(c.slam.size());
    const DeadReckoning dr = deadReckoning(c);
    // Association against the labels, with the landmark assignment of the map figures above.
    const bool have_assoc = !c.associations.empty() && !c.labels.empty() && c.have_slam_map && c.have_truth_map;
    eval::AssociationScore as;
    if (have_assoc) {
      std::map<int64_t, int64_t> truth_of_estimate;
      for (size_t i = 0; i < me.truth_of_estimate.size() && i < c.slam_map_ids.size(); ++i)
        if (me.truth_of_estimate[i] >= 0)
          truth_of_estimate[c.slam_map_ids[i]] = c.truth_map_ids[static_cast<size_t>(me.truth_of_estimate[i])];
      std::vector<std::vector<int64_t>> a, l;
      for (const auto& [u, lab] : c.labels) {
        const auto it = c.associations.find(u);
        if (it == c.associations.end()) continue;  // a frame the SLAM did not answer (dropped)
        a.push_back(it->second);
        l.push_back(lab);
      }
      as = eval::scoreAssociations(a, l, truth_of_estimate);
    }
    // Every figure printed is a number: a non-finite one is an error with its name, never "inf" or "-nan".
    std::vector<std::pair<const char*, double>> figures{
        {"ate_rmse_m", te.ate_rmse_m}, {"ate_max_m", te.ate_max_m}, {"heading_rmse_rad", te.heading_rmse_rad},
        {"heading_max_rad", te.heading_max_rad}, {"landmark_mean_err_m", me.mean_err_m}, {"landmark_max_err_m", me.max_err_m}};
    for (double e : te.position_error_m) figures.push_back({"a position error", e});
    if (dr.available)
      figures.insert(figures.end(), {{"dr_ate_rmse_m", dr.raw.ate_rmse_m}, {"dr_ate_max_m", dr.raw.ate_max_m},
                                     {"dr_heading_rmse_rad", dr.raw.heading_rmse_rad},
                                     {"dr_ate_rmse_aligned_m", dr.aligned.ate_rmse_m},
                                     {"dr_ate_max_aligned_m", dr.aligned.ate_max_m}});
    for (const auto& [name, v] : figures)
      if (!std::isfinite(v))
        throw std::invalid_argument(std::string(name) + " is not finite: positions too large to compare");
    if (!no_tum) {
      const std::string prefix = tum_prefix.empty() ? log : tum_prefix;
      writeTum(prefix + ".slam.tum", c.slam);
      writeTum(prefix + ".truth.tum", c.truth);
      if (dr.available) writeTum(prefix + ".odometry.tum", dr.poses);
    }
    if (!plot_prefix.empty()) {
      vision::MapPlot mp;
      mp.title = log + (T ? "  (aligned)" : "");
      for (const auto& p : c.slam) mp.estimate.push_back(p.pose);
      for (const auto& p : c.truth) mp.truth.push_back(p.pose);
      for (size_t i = 0; i < c.slam_map.size(); ++i) {
        vision::PlotLandmark l;
        l.p_m = c.slam_map[i];
        if (i < c.slam_map_cov_xy.size()) {
          Eigen::Matrix2d cov = c.slam_map_cov_xy[i];
          if (T) {  // rotate the covariance with the alignment
            const Eigen::Matrix2d R = Eigen::Rotation2Dd(T->theta_rad).toRotationMatrix();
            cov = R * cov * R.transpose();
          }
          l.cov_xy_m2 = cov;
        }
        mp.estimated_landmarks.push_back(l);
      }
      mp.true_landmarks = c.truth_map;
      vision::ErrorPlot ep;
      ep.title = "errors over time";
      for (size_t i = 0; i < pairs.size(); ++i) {
        ep.t_s.push_back((pairs[i].utime - pairs.front().utime) * 1e-6);
        ep.position_err_m.push_back(te.position_error_m[i]);
        ep.heading_err_rad.push_back(te.heading_error_rad[i]);
      }
      if (!cv::imwrite(plot_prefix + ".map.png", vision::renderMapPlot(mp)) ||
          !cv::imwrite(plot_prefix + ".errors.png", vision::renderErrorPlot(ep)))
        throw std::runtime_error("--plot: cannot write PNG files with prefix '" + plot_prefix + "'");
    }
    std::ostringstream o;
    o << std::setprecision(6);
    if (json) {
      o << "{\"ate_rmse_m\": " << te.ate_rmse_m << ", \"ate_max_m\": " << te.ate_max_m
        << ", \"heading_rmse_rad\": " << te.heading_rmse_rad << ", \"heading_max_rad\": " << te.heading_max_rad
        << ", \"landmark_mean_err_m\": " << me.mean_err_m << ", \"landmark_max_err_m\": " << me.max_err_m
        << ", \"landmarks_matched\": " << me.matched << ", \"landmarks_truth\": " << me.truth
        << ", \"landmarks_estimated\": " << me.estimated << ", \"landmarks_spurious\": " << me.spurious
        << ", \"frames\": " << frames << ", \"frames_with_pose\": " << c.slam.size()
        << ", \"poses_compared\": " << te.pairs << ", \"messages_skipped\": " << c.skippedTotal() << ", \"log_unreadable_bytes\": " << c.unreadable_bytes
        << ", \"aligned\": " << (T ? "true" : "false");
      if (T) o << ", \"align_theta_rad\": " << T->theta_rad << ", \"align_tx_m\": " << T->t_m.x() << ", \"align_ty_m\": " << T->t_m.y();
      o << ", \"map_available\": " << (c.have_slam_map && c.have_truth_map ? "true" : "false");
      o << ", \"dr_available\": " << (dr.available ? "true" : "false");
      if (dr.available)
        o << ", \"dr_ate_rmse_m\": " << dr.raw.ate_rmse_m << ", \"dr_ate_max_m\": " << dr.raw.ate_max_m
          << ", \"dr_heading_rmse_rad\": " << dr.raw.heading_rmse_rad
          << ", \"dr_ate_rmse_aligned_m\": " << dr.aligned.ate_rmse_m
          << ", \"dr_ate_max_aligned_m\": " << dr.aligned.ate_max_m << ", \"dr_poses_compared\": " << dr.raw.pairs;
      o << ", \"assoc_available\": " << (have_assoc ? "true" : "false");
      if (have_assoc)
        o << ", \"assoc_precision\": " << as.precision() << ", \"assoc_recall\": " << as.recall()
          << ", \"assoc_frames\": " << as.frames << ", \"assoc_frames_mismatched\": " << as.frames_mismatched
          << ", \"assoc_features\": " << as.features
          << ", \"assoc_true_landmark_features\": " << as.true_landmark_features
          << ", \"assoc_associated\": " << as.associated << ", \"assoc_correct\": " << as.correct
          << ", \"assoc_clutter_associated\": " << as.clutter_associated;
      o << "}\n";
    } else {
      o << "omnislam-eval " << log << (T ? "  (aligned)" : "") << "\n";
      if (c.unreadable_bytes > 0)
        o << "  the log's last " << c.unreadable_bytes << " bytes cannot be read (truncated or corrupt; stderr)\n";
      if (c.skippedTotal() > 0)
        o << "  skipped " << c.skippedTotal() << " undecodable, invalid or replaced messages (listed on stderr)\n";
      o << "  trajectory: " << te.pairs << " poses compared of " << c.slam.size() << " (" << frames << " frames)\n";
      o << "    ATE RMSE " << te.ate_rmse_m << " m, max " << te.ate_max_m << " m\n";
      o << "    heading RMSE " << te.heading_rmse_rad << " rad, max " << te.heading_max_rad << " rad\n";
      if (!c.have_truth_map) {  // nothing to compare with: no "0 true" and no 0 m error
        o << "  map: " << me.estimated << " estimated; no truth map (no GROUND_TRUTH_MAP)\n";
      } else {
        o << "  map: " << me.estimated << " estimated, " << me.truth << " true, " << me.matched << " matched within "
          << gate_m << " m, " << me.spurious << " spurious\n";
        if (me.matched > 0)
          o << "    landmark error mean " << me.mean_err_m << " m, max " << me.max_err_m << " m\n";
        else
          o << "    landmark error n/a (no landmark matched)\n";
      }
      if (T) o << "  alignment: rotation " << T->theta_rad << " rad, translation (" << T->t_m.x() << ", " << T->t_m.y() << ") m\n";
      if (dr.available)
        o << "  dead reckoning (ODOMETRY from the start pose): ATE RMSE " << dr.raw.ate_rmse_m << " m, max "
          << dr.raw.ate_max_m << " m; aligned: RMSE " << dr.aligned.ate_rmse_m << " m, max " << dr.aligned.ate_max_m
          << " m\n";
      if (have_assoc)
        o << "  association: precision " << ratioText(as.precision(), as.associated) << " (" << as.correct << "/"
          << as.associated << "), recall " << ratioText(as.recall(), as.true_landmark_features) << " (" << as.correct
          << "/" << as.true_landmark_features << "); " << as.clutter_associated << " clutter features associated; "
          << as.frames << " frames, " << as.frames_mismatched << " left out (feature counts differ)\n";
    }
    std::cout << o.str();
    return 0;
  });
}
