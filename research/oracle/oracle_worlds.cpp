// research_oracle_worlds: replays a feature log of omnislam-gen-world through the shipped filter's
// step with an oracle association and/or map (oracle_filter.h) and writes what omnislam-slam --replay
// writes for omnislam-eval (the input events, SLAM_POSE, SLAM_MAP, SLAM_ASSOCIATIONS), so that
// research/oracle-worlds.sh scores the oracles exactly as scripts/evaluate-worlds.sh scores the
// filter. Issue 45 ("What an oracle reaches", docs/results/world-families.md). Usage:
//   research_oracle_worlds --config C.yaml --in LOG.lcm --out OUT.lcm [--seed N] [--set K=V ...]
//       [--association filter|truth] [--map build|truth] [--birth filter|truth] [--fit-json FIT.json]
//       [--association-method hungarian|ml]
// --association truth: each feature to its lamp (GROUND_TRUTH_FEATURE_LABELS), clutter dropped.
// --birth truth: (with --association truth) a candidate the filter initialises is born at its lamp.
// --map truth: localisation only on the lamps of GROUND_TRUTH_MAP at their true positions.
// --fit-json: the final map's rotation about the start (best fit to the lamps, as noise_free_hall).
// --graph-json: the back end's keyframe graph of the whole run (every filter step a keyframe) with
//   the TRUE association (each labelled feature to its lamp, clutter left out), poses and lamps
//   starting at the truth, solved once at the end by the product's smoother (backend.solver and
//   backend.odometry_calibration of the config): what the graph's formulation reaches when its
//   association is right (issue 54). Keyframe position / heading RMSE and lamp errors against the truth.
#include <CLI/CLI.hpp>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "omnislam/associations_t.hpp"
#include "omnislam/core/angles.h"
#include "omnislam/runtime/slam_config.h"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/decode.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/map_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/runtime/map_message.h"
#include "omnislam/runtime/pairing.h"
#include "omnislam/runtime/slam_driver.h"
#include "omnislam/smoothing/keyframe_graph.h"
#include "oracle_filter.h"

using namespace omnislam;
using research::OracleFilter;

namespace {

struct Args {
  std::string config, in, out, fit_json, graph_json, graph_init = "truth", graph_cov = "estimate",
                                                     association = "filter", map = "build", birth = "filter", method;
  std::vector<std::string> sets;
  std::uint64_t seed = 1;
  int reweight = 0;
};

/// What the first pass takes from the log: the labels of each frame (by utime) and the lamps.
struct Truth {
  std::map<int64_t, std::vector<int64_t>> labels;
  std::vector<slam::Landmark> lamps;  ///< id = lamp id, at its true position
  std::map<int64_t, Pose2> poses;     ///< GROUND_TRUTH_POSE by utime
  Eigen::Vector3d p_CinR_m = Eigen::Vector3d::Zero();
};

Truth readTruth(const std::string& path) {
  Truth t;
  lcmio::forEachEvent(path, [&](const lcmio::LogEvent& ev) {
    if (ev.channel == channels::kGroundTruthFeatureLabels) {
      if (auto m = lcmio::decodeAs<feature_labels_t>(ev)) t.labels[m->utime] = m->landmark_id;
    } else if (ev.channel == channels::kGroundTruthPose) {
      if (auto m = lcmio::decodeAs<pose_t>(ev)) t.poses[m->utime] = Pose2{m->x_m, m->y_m, m->theta_rad};
    } else if (ev.channel == channels::kOmniFeatures) {
      if (auto m = lcmio::decodeAs<features_t>(ev))
        t.p_CinR_m = Eigen::Vector3d(m->camera_position_m[0], m->camera_position_m[1], m->camera_position_m[2]);
    } else if (ev.channel == channels::kGroundTruthMap && t.lamps.empty()) {
      if (auto m = lcmio::decodeAs<map_t>(ev))
        for (const landmark_t& l : m->landmarks) {
          slam::Landmark L;
          L.id = static_cast<std::uint64_t>(l.id);
          L.p_LinW_m = Eigen::Vector3d(l.position_m[0], l.position_m[1], l.position_m[2]);
          L.cov_LinW_m2 = Eigen::Matrix3d::Identity() * 1e-6;  // 1 mm: known, not updated (update_map off)
          L.counter = 1000;
          L.descriptor = research::labelDescriptor(l.id);
          t.lamps.push_back(L);
        }
    }
  });
  return t;
}

map_t mapMessage(const OracleFilter& f, int64_t utime, int64_t seq, int64_t input_seq) {
  return runtime::toMapMessage(f.bestMap(), f.bestCandidateCount(), utime, seq, input_seq);
}

pose_t poseMessage(const OracleFilter& f, int64_t utime, int64_t seq, int64_t input_seq, double ess) {
  pose_t p{};
  const Pose2 mean = f.meanPose();
  const Eigen::Matrix3d cov = f.poseCovariance();
  p.utime = utime;
  p.seq = seq;
  p.x_m = mean.x_m;
  p.y_m = mean.y_m;
  p.theta_rad = mean.theta_rad;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) p.covariance[i][j] = cov(i, j);
  p.num_particles = f.numParticles();
  p.effective_sample_size = ess;
  p.input_seq = input_seq;
  return p;
}

/// --birth truth: landmarks born at their lamps.
research::Birth birthOf(const Args& a, const Truth& t) {
  if (a.birth != "truth") return research::FilterBirth{};
  research::TruthBirth b;
  for (const auto& L : t.lamps) b.p_LinW_m[static_cast<int64_t>(L.id)] = L.p_LinW_m;
  return b;
}

/// The replay: input events copied to the output, frames paired with odometry as omnislam-slam
/// pairs them (runtime::Pairer), one filter step per paired frame, its outputs at the event's time.
class Replay {
 public:
  Replay(const runtime::SlamProcessOptions& opt, const Args& a, Truth truth)
      : opt_(opt),
        truth_(std::move(truth)),
        by_label_(a.association == "truth"),
        truth_map_(a.map == "truth"),
        filter_(opt.filter, opt.seed,
                by_label_ ? research::Association{research::TruthAssociation{}} : research::FilterAssociation{},
                birthOf(a, truth_)),
        pairer_(opt.pairing),
        out_(a.out, lcmio::LogWriter::Mode::kAtomic),
        record_graph_(!a.graph_json.empty()),
        graph_init_filter_(a.graph_init == "filter") {}

  void event(const lcmio::LogEvent& ev) {
    if (ev.channel.rfind("SLAM_", 0) == 0) return;
    out_.write(ev.log_utime, ev.channel, ev.data.data(), static_cast<int32_t>(ev.data.size()));
    last_ts_ = ev.log_utime;
    std::vector<runtime::PairEvent> events;
    if (ev.channel == channels::kOdometry) {
      if (auto m = lcmio::decodeValid<odometry_t>(ev))
        pairer_.addOdometry(m->utime, Pose2{m->x_m, m->y_m, m->theta_rad}, events);
    } else if (ev.channel == channels::kOmniFeatures) {
      if (auto m = lcmio::decodeValid<features_t>(ev)) pairer_.addFrame(runtime::toFrame(*m, opt_), events);
    }
    apply(events);
  }

  /// End of input: pending frames decided, the log committed; the final best map.
  std::vector<slam::Landmark> finish() {
    std::vector<runtime::PairEvent> events;
    pairer_.finish(events);
    apply(events);
    out_.commit();
    std::cerr << "research_oracle_worlds: " << frames_ << " frames, " << dropped_ << " dropped, "
              << filter_.bestMap().size() << " landmarks" << std::endl;
    return filter_.bestMap();
  }

  /// --graph-json: one record per filter step, the true labels as the association, at the true pose.
  const std::vector<smoothing::KeyframeRecord>& graphRecords() const { return graph_records_; }
  const std::vector<Pose2>& graphTruth() const { return graph_truth_; }

 private:
  /// The truth pose nearest to `utime` (GROUND_TRUTH_POSE runs at 50 Hz; frames fall on it).
  Pose2 truthPoseAt(int64_t utime) const {
    auto it = truth_.poses.lower_bound(utime);
    if (it == truth_.poses.end()) --it;
    if (it != truth_.poses.begin() && std::prev(it)->first - utime > utime - it->first) --it;
    return it->second;
  }

  void recordGraph(const runtime::Frame& fr, const Pose2& odom_O) {
    const auto labels = truth_.labels.find(fr.utime);
    if (labels == truth_.labels.end()) throw std::runtime_error("--graph-json: frame without labels");
    smoothing::KeyframeRecord r;
    r.utime = fr.utime;
    r.odom_O = odom_O;
    r.T_WtoR_filter = graph_init_filter_ ? filter_.meanPose() : truthPoseAt(fr.utime);
    graph_truth_.push_back(truthPoseAt(fr.utime));
    r.z = fr.z;
    for (std::size_t k = 0; k < fr.z.size(); ++k) {
      const auto f = static_cast<std::size_t>(fr.feature_index[k]);
      r.landmark_of_measurement.push_back(f < labels->second.size() ? labels->second[f] : -1);
    }
    graph_records_.push_back(std::move(r));
  }

  void apply(std::vector<runtime::PairEvent>& events) {
    for (auto& e : events) {
      if (e.kind == runtime::PairEvent::Kind::kReset) throw std::runtime_error("input restarted: not supported");
      if (e.kind == runtime::PairEvent::Kind::kDropped) ++dropped_;
      if (e.kind == runtime::PairEvent::Kind::kPaired) process(e.frame, e.odom_O);
    }
  }

  /// The features the filter sees: all (filter association), or the labelled ones carrying their label.
  std::vector<slam::BearingMeasurement> measurements(const runtime::Frame& fr, std::vector<int32_t>& index) const {
    if (!by_label_) {
      index = fr.feature_index;
      return fr.z;
    }
    const auto it = truth_.labels.find(fr.utime);
    if (it == truth_.labels.end()) throw std::runtime_error("frame without GROUND_TRUTH_FEATURE_LABELS");
    std::vector<slam::BearingMeasurement> z;
    for (std::size_t k = 0; k < fr.z.size(); ++k) {
      const auto f = static_cast<std::size_t>(fr.feature_index[k]);
      if (f >= it->second.size() || it->second[f] < 0) continue;  // clutter (UNKNOWN) dropped
      z.push_back(fr.z[k]);
      z.back().descriptor = research::labelDescriptor(it->second[f]);
      index.push_back(fr.feature_index[k]);
    }
    return z;
  }

  void process(const runtime::Frame& fr, const Pose2& odom_O) {
    if (frames_ == 0) {
      const bool fixed = opt_.start_source == runtime::SlamProcessOptions::StartSource::kFixed;
      filter_.initialise(fixed ? opt_.start_pose_W : odom_O, truth_map_ ? truth_.lamps : std::vector<slam::Landmark>{});
      odom_prev_ = odom_O;
    }
    std::vector<int32_t> index;
    const std::vector<slam::BearingMeasurement> z = measurements(fr, index);
    const research::OracleStep st = filter_.step(odom_prev_, odom_O, z);
    odom_prev_ = odom_O;
    if (record_graph_) recordGraph(fr, odom_O);
    out_.write(last_ts_, channels::kSlamPose, poseMessage(filter_, fr.utime, frames_, fr.seq, st.ess));
    if (frames_ % opt_.map_every_n_frames == 0)
      out_.write(last_ts_, channels::kSlamMap, mapMessage(filter_, fr.utime, map_seq_++, fr.seq));
    associations_t a{};
    a.utime = fr.utime;
    a.seq = frames_;
    a.input_seq = fr.seq;
    a.num_features = fr.num_features;
    a.landmark_id.assign(static_cast<std::size_t>(fr.num_features), +associations_t::NOT_USED);
    for (std::size_t k = 0; k < fr.feature_index.size(); ++k)
      a.landmark_id[static_cast<std::size_t>(fr.feature_index[k])] = +associations_t::NOT_ASSOCIATED;
    for (std::size_t k = 0; k < index.size(); ++k) {
      const int64_t id = st.landmark_of_measurement[k];
      a.landmark_id[static_cast<std::size_t>(index[k])] = id >= 0 ? id : +associations_t::NOT_ASSOCIATED;
    }
    out_.write(last_ts_, channels::kSlamAssociations, a);
    ++frames_;
  }

  const runtime::SlamProcessOptions& opt_;
  Truth truth_;
  bool by_label_, truth_map_;
  OracleFilter filter_;
  runtime::Pairer pairer_;
  lcmio::LogWriter out_;
  bool record_graph_, graph_init_filter_;
  std::vector<Pose2> graph_truth_;
  std::vector<smoothing::KeyframeRecord> graph_records_;
  Pose2 odom_prev_;
  int64_t last_ts_ = 0, frames_ = 0, dropped_ = 0, map_seq_ = 0;
};

/// How a lamp was seen (from the truth): detections, pairs of detections whose true camera centres
/// subtend more than ANG_min at the lamp (counted up to NCROSS_valid), the largest such angle, the
/// nearest camera. Detections are thinned to <= 300 per lamp.
struct LampSight {
  int detections = 0, wide_pairs = 0;
  double max_parallax_deg = 0.0, min_range_m = 0.0;
};

LampSight lampSight(const std::vector<Eigen::Vector3d>& centres, const Eigen::Vector3d& lamp,
                    const slam::CandidateOptions& c) {
  LampSight s;
  s.detections = static_cast<int>(centres.size());
  std::vector<Eigen::Vector3d> dirs;
  s.min_range_m = 1e9;
  for (std::size_t i = 0; i < centres.size(); i += std::max<std::size_t>(1, centres.size() / 300)) {
    dirs.push_back((centres[i] - lamp).normalized());
    s.min_range_m = std::min(s.min_range_m, (centres[i] - lamp).norm());
  }
  double min_dot = 1.0;
  const double cos_min = std::cos(c.min_parallax_rad);
  for (std::size_t i = 0; i < dirs.size(); ++i)
    for (std::size_t j = i + 1; j < dirs.size(); ++j) {
      const double d = dirs[i].dot(dirs[j]);
      min_dot = std::min(min_dot, d);
      s.wide_pairs += d < cos_min && s.wide_pairs < c.ncross_valid;
    }
  s.max_parallax_deg = std::acos(std::clamp(min_dot, -1.0, 1.0)) * 180.0 / M_PI;
  return s;
}

/// Every lamp detected in >= 3 frames, with how it was seen.
std::map<int64_t, LampSight> lampSights(const Truth& t, const slam::CandidateOptions& c) {
  std::map<int64_t, std::vector<Eigen::Vector3d>> centres;
  for (const auto& [utime, ids] : t.labels) {
    const auto pose = t.poses.find(utime);
    if (pose == t.poses.end()) continue;
    for (const int64_t id : ids)
      if (id >= 0) centres[id].push_back(slam::cameraCentreInWorld(pose->second, t.p_CinR_m));
  }
  std::map<int64_t, LampSight> out;
  for (const auto& L : t.lamps) {
    const auto it = centres.find(static_cast<int64_t>(L.id));
    if (it != centres.end() && it->second.size() >= 3) out[it->first] = lampSight(it->second, L.p_LinW_m, c);
  }
  return out;
}

/// The lamps seen 3x that fewer than NCROSS_valid wide pairs leave beyond the delayed initialisation
/// (a necessary condition of candidate.h's validity a): the filter's window of rays sees fewer), and,
/// with the truth association (landmarks carry their label), those not in the final map.
std::string sightJson(const std::map<int64_t, LampSight>& sights, const std::vector<slam::Landmark>& map, bool labelled,
                      int ncross_valid) {
  std::set<int64_t> mapped;
  for (const auto& L : map) mapped.insert(research::labelOf(L.descriptor));
  int starved = 0;
  std::ostringstream o;
  o.precision(4);
  o << "\"unmapped_seen_3\": [";
  const char* sep = "";
  for (const auto& [id, s] : sights) {
    starved += s.wide_pairs < ncross_valid;
    if (!labelled || mapped.count(id)) continue;
    o << sep << "{\"id\": " << id << ", \"detections\": " << s.detections << ", \"wide_pairs\": " << s.wide_pairs
      << ", \"max_parallax_deg\": " << s.max_parallax_deg << ", \"min_range_m\": " << s.min_range_m << "}";
    sep = ", ";
  }
  o << "]";
  return "\"lamps_seen_3\": " + std::to_string(sights.size()) +
         ", \"lamps_seen_3_parallax_starved\": " + std::to_string(starved) + ", " + o.str();
}

/// The map's rotation about the start: landmarks matched to their nearest lamp within 2 m, the
/// rotation about the start position that best aligns them in x-y (as research/noise_free_hall.cpp),
/// and the mean error before and after removing it. JSON on one line.
std::string mapFitJson(const std::vector<slam::Landmark>& map, const std::vector<slam::Landmark>& lamps,
                       const Eigen::Vector2d& start, const std::string& sights) {
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> pairs;  // (estimate, lamp) about the start
  for (const auto& lm : map) {
    double best = 2.0;
    const slam::Landmark* bl = nullptr;
    for (const auto& t : lamps)
      if ((lm.p_LinW_m - t.p_LinW_m).norm() < best) best = (lm.p_LinW_m - t.p_LinW_m).norm(), bl = &t;
    if (bl) pairs.push_back({lm.p_LinW_m.head<2>() - start, bl->p_LinW_m.head<2>() - start});
  }
  double sxx = 0, sxy = 0, mean = 0, mean_derotated = 0;
  for (const auto& [e, t] : pairs) {  // the rotation taking t onto e
    sxx += t.dot(e);
    sxy += t.x() * e.y() - t.y() * e.x();
  }
  const double a = pairs.empty() ? 0.0 : std::atan2(sxy, sxx);
  const Eigen::Rotation2Dd R(-a);
  for (const auto& [e, t] : pairs) {
    mean += (e - t).norm() / static_cast<double>(pairs.size());
    mean_derotated += (R * e - t).norm() / static_cast<double>(pairs.size());
  }
  std::ostringstream o;
  o.precision(6);
  o << "{\"map_rotation_deg\": " << a * 180.0 / M_PI << ", \"fit_matched\": " << pairs.size()
    << ", \"fit_mean_xy_m\": " << mean << ", \"fit_mean_derotated_xy_m\": " << mean_derotated << ", " << sights
    << "}\n";
  return o.str();
}

/// --graph-json: the keyframe graph of the whole run with the true association, solved from the
/// truth; its keyframes and located lamps against the truth. JSON on one line.
std::string graphJson(const std::vector<smoothing::KeyframeRecord>& records, const std::vector<Pose2>& truth,
                      const std::vector<slam::Landmark>& lamps, const runtime::SlamProcessOptions& opt,
                      bool at_measured, int reweight_rounds) {
  smoothing::GraphOptions g;
  g.motion = opt.filter.motion;
  g.start = truth.front();
  g.covariance_window = opt.backend.odometry_covariance_window;
  if (at_measured) g.odometry_covariance_at = smoothing::OdometryCovarianceAt::kMeasured;
  g.ceiling = opt.backend.ceilingPrior();
  g.calibrate_odometry = opt.backend.odometry_calibration == smoothing::OdometryCalibration::kScaleAndDrift;
  smoothing::Graph graph;
  smoothing::Solution s;
  std::vector<smoothing::KeyframeRecord> rs = records;
  std::vector<slam::Landmark> ls = lamps;
  for (int round = 0; round <= reweight_rounds; ++round) {  // Sigma_u at the last solution's increments
    smoothing::KeyframeGraph kg(g);
    for (const auto& r : rs) kg.add(r);
    graph = kg.build(ls);
    s = smoothing::solve(graph, opt.backend.solver);
    if (!s.ok) throw std::runtime_error("--graph-json: the solve failed: " + s.failure);
    for (std::size_t k = 0; k < rs.size(); ++k) rs[k].T_WtoR_filter = s.keyframe_poses[k];
    for (std::size_t j = 0; j < ls.size() && j < s.landmarks_m.size(); ++j) ls[j].p_LinW_m = s.landmarks_m[j];
  }
  double pos2 = 0.0, head2 = 0.0, lamp_sum = 0.0, lamp_max = 0.0, st = 0.0, tt = 0.0, odo_len = 0.0, true_len = 0.0;
  const Eigen::Vector2d p0(g.start.x_m, g.start.y_m);
  for (std::size_t k = 0; k < records.size(); ++k) {
    const Pose2& t = truth[k];
    const Eigen::Vector2d dt = Eigen::Vector2d(t.x_m, t.y_m) - p0;
    st += (Eigen::Vector2d(s.keyframe_poses[k].x_m, s.keyframe_poses[k].y_m) - p0).dot(dt);
    tt += dt.squaredNorm();
    if (k > 0) {
      const Pose2& a = records[k - 1].odom_O;
      const Pose2& b = records[k].odom_O;
      const Pose2& ta = truth[k - 1];
      const Eigen::Vector2d u = Eigen::Rotation2Dd(-a.theta_rad) * Eigen::Vector2d(b.x_m - a.x_m, b.y_m - a.y_m);
      const Eigen::Vector2d v = Eigen::Rotation2Dd(-ta.theta_rad) * Eigen::Vector2d(t.x_m - ta.x_m, t.y_m - ta.y_m);
      odo_len += u.dot(v);
      true_len += v.squaredNorm();
    }
    pos2 += std::pow(s.keyframe_poses[k].x_m - t.x_m, 2) + std::pow(s.keyframe_poses[k].y_m - t.y_m, 2);
    head2 += std::pow(wrapAngle(s.keyframe_poses[k].theta_rad - t.theta_rad), 2);
  }
  for (std::size_t j = 0; j < graph.landmarks.size(); ++j) {
    const double e = (s.landmarks_m[j] - lamps[j].p_LinW_m).norm();  // build() keeps the map's order
    lamp_sum += e;
    lamp_max = std::max(lamp_max, e);
  }
  std::size_t dof = 0;
  for (const auto& b : graph.bearings) dof += b.z.kind == slam::LandmarkKind::kPoint3D ? 2 : 1;
  dof += 3 * graph.odometry.size();
  std::ostringstream o;
  o.precision(6);
  const double n = static_cast<double>(records.size());
  o << "{\"graph_keyframes\": " << records.size() << ", \"graph_lamps\": " << graph.landmarks.size()
    << ", \"graph_bearings\": " << graph.bearings.size() << ", \"graph_removed\": " << s.removed.size()
    << ", \"graph_position_rmse_m\": " << std::sqrt(pos2 / n)
    << ", \"graph_heading_rmse_deg\": " << std::sqrt(head2 / n) * 180.0 / M_PI
    << ", \"graph_lamp_mean_m\": " << lamp_sum / std::max<double>(1.0, static_cast<double>(graph.landmarks.size()))
    << ", \"graph_lamp_max_m\": " << lamp_max << ", \"graph_scale_about_start\": " << st / std::max(tt, 1e-12)
    << ", \"odometry_path_ratio\": " << odo_len / true_len
    << ", \"graph_2cost_over_dof\": " << 2.0 * s.final_cost / static_cast<double>(std::max<std::size_t>(1, dof));
  if (s.odometry_calibration)
    o << ", \"graph_odometry_scale\": " << (*s.odometry_calibration)(0)
      << ", \"graph_drift_rad_per_m\": " << (*s.odometry_calibration)(1);
  o << "}\n";
  return o.str();
}

int run(const Args& a) {
  if (a.association != "filter" && a.association != "truth") throw std::invalid_argument("--association filter|truth");
  if (a.map != "build" && a.map != "truth") throw std::invalid_argument("--map build|truth");
  if (a.birth != "filter" && !(a.birth == "truth" && a.association == "truth"))
    throw std::invalid_argument("--birth filter|truth (truth needs --association truth)");
  runtime::SlamProcessOptions opt = runtime::loadSlamOptions(a.config, a.sets);
  opt.seed = a.seed;
  if (!a.method.empty()) opt.filter.association = runtime::associationFromName(a.method);
  if (a.map == "truth") opt.filter.update_map = false;  // localisation only
  if (const std::string err = opt.validate(); !err.empty()) throw std::invalid_argument(err);
  Truth truth = readTruth(a.in);
  const std::vector<slam::Landmark> lamps = truth.lamps;
  const std::map<int64_t, LampSight> sights = lampSights(truth, opt.filter.candidates);
  Replay replay(opt, a, std::move(truth));
  lcmio::forEachEvent(a.in, [&](const lcmio::LogEvent& ev) { replay.event(ev); });
  const std::vector<slam::Landmark> map = replay.finish();
  if (!a.graph_json.empty()) {
    std::ofstream f(a.graph_json);
    f << graphJson(replay.graphRecords(), replay.graphTruth(), lamps, opt, a.graph_cov == "measured", a.reweight);
    if (!f) throw std::runtime_error("cannot write " + a.graph_json);
  }
  if (!a.fit_json.empty()) {
    std::ofstream f(a.fit_json);
    f << mapFitJson(
        map, lamps, Eigen::Vector2d(opt.start_pose_W.x_m, opt.start_pose_W.y_m),
        sightJson(sights, map, a.association == "truth" && a.map == "build", opt.filter.candidates.ncross_valid));
    if (!f) throw std::runtime_error("cannot write " + a.fit_json);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"research_oracle_worlds: the shipped filter with a truth association and/or map (issue 45)"};
  Args a;
  cli.add_option("--config", a.config, "SLAM config (config/slam/sports_hall.yaml)")->required();
  cli.add_option("--in", a.in, "feature log of omnislam-gen-world")->required();
  cli.add_option("--out", a.out, "output log for omnislam-eval")->required();
  cli.add_option("--seed", a.seed, "filter seed");
  cli.add_option("--set", a.sets, "config override KEY=VALUE (repeatable)");
  cli.add_option("--association", a.association, "filter | truth");
  cli.add_option("--association-method", a.method, "the filter association's method: hungarian | ml");
  cli.add_option("--map", a.map, "build | truth");
  cli.add_option("--birth", a.birth, "filter | truth: landmarks born where the filter puts them, or at their lamps");
  cli.add_option("--fit-json", a.fit_json, "write the final map's rotation about the start here");
  cli.add_option("--graph-json", a.graph_json, "solve the whole run's keyframe graph with the true association here");
  cli.add_option("--graph-init", a.graph_init, "truth | filter: the keyframes' initial poses (and Sigma_u's estimate)");
  cli.add_option("--graph-reweight", a.reweight, "solves again with Sigma_u at the last solution, this many times");
  cli.add_option("--graph-cov", a.graph_cov, "estimate | measured: where the odometry covariance is evaluated");
  CLI11_PARSE(cli, argc, argv);
  try {
    return run(a);
  } catch (const std::exception& e) {
    std::cerr << "research_oracle_worlds: " << e.what() << std::endl;
    return 2;
  }
}
