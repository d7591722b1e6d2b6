// SLAM process config parsing: see slam_config.h and docs/slam-process.md.
#include "omnislam/config/slam_config.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>

#include "omnislam/core/angles.h"

namespace omnislam::slamproc {

namespace {

using config::ConfigError;
using config::Node;

int64_t seconds_us(const Node& n, const std::string& key, double lo, double hi, int64_t def_us) {
  return static_cast<int64_t>(std::llround(n.getDouble(key, lo, hi, static_cast<double>(def_us) * 1e-6) * 1e6));
}

void parseMotion(const Node& n, slam::MotionNoiseOptions& m) {
  n.rejectUnknownKeys({"model", "err_tran_per_m", "err_rot_per_rad", "err_drift_rad_per_m", "err_tran_per_sqrt_m",
                       "err_rot_per_sqrt_rad", "err_drift_rad_per_sqrt_m", "trans_sigma_per_m", "lateral_sigma_per_m", "trans_sigma_per_rad", "rot_sigma_per_rad",
                       "rot_sigma_per_m", "trans_sigma_per_sqrt_m", "lateral_sigma_per_sqrt_m", "rot_sigma_per_sqrt_rad",
                       "rot_sigma_per_sqrt_m", "min_sigma_xy_m", "min_sigma_theta_rad"});
  const std::string model = n.getEnum("model", {"chord", "translate_then_rotate"},
                                      m.model == slam::MotionNoiseModel::kChord ? "chord" : "translate_then_rotate");
  m.model = model == "translate_then_rotate" ? slam::MotionNoiseModel::kTranslateThenRotate
                                             : slam::MotionNoiseModel::kChord;
  m.err_tran_per_m = n.getDouble("err_tran_per_m", 0.0, 10.0, m.err_tran_per_m);
  m.err_rot_per_rad = n.getDouble("err_rot_per_rad", 0.0, 10.0, m.err_rot_per_rad);
  m.err_drift_rad_per_m = n.getDouble("err_drift_rad_per_m", 0.0, 10.0, m.err_drift_rad_per_m);
  m.err_tran_per_sqrt_m = n.getDouble("err_tran_per_sqrt_m", 0.0, 10.0, m.err_tran_per_sqrt_m);
  m.err_rot_per_sqrt_rad = n.getDouble("err_rot_per_sqrt_rad", 0.0, 10.0, m.err_rot_per_sqrt_rad);
  m.err_drift_rad_per_sqrt_m = n.getDouble("err_drift_rad_per_sqrt_m", 0.0, 10.0, m.err_drift_rad_per_sqrt_m);
  m.trans_sigma_per_m = n.getDouble("trans_sigma_per_m", 0.0, 10.0, m.trans_sigma_per_m);
  m.lateral_sigma_per_m = n.getDouble("lateral_sigma_per_m", 0.0, 10.0, m.lateral_sigma_per_m);
  m.trans_sigma_per_rad = n.getDouble("trans_sigma_per_rad", 0.0, 10.0, m.trans_sigma_per_rad);
  m.rot_sigma_per_rad = n.getDouble("rot_sigma_per_rad", 0.0, 10.0, m.rot_sigma_per_rad);
  m.rot_sigma_per_m = n.getDouble("rot_sigma_per_m", 0.0, 10.0, m.rot_sigma_per_m);
  m.trans_sigma_per_sqrt_m = n.getDouble("trans_sigma_per_sqrt_m", 0.0, 10.0, m.trans_sigma_per_sqrt_m);
  m.lateral_sigma_per_sqrt_m = n.getDouble("lateral_sigma_per_sqrt_m", 0.0, 10.0, m.lateral_sigma_per_sqrt_m);
  m.rot_sigma_per_sqrt_rad = n.getDouble("rot_sigma_per_sqrt_rad", 0.0, 10.0, m.rot_sigma_per_sqrt_rad);
  m.rot_sigma_per_sqrt_m = n.getDouble("rot_sigma_per_sqrt_m", 0.0, 10.0, m.rot_sigma_per_sqrt_m);
  m.min_sigma_xy_m = n.getDouble("min_sigma_xy_m", 1e-9, 10.0, m.min_sigma_xy_m);
  m.min_sigma_theta_rad = n.getDouble("min_sigma_theta_rad", 1e-9, 10.0, m.min_sigma_theta_rad);
}

void parsePerception(const Node& n, slam::PerceptionOptions& p) {
  n.rejectUnknownKeys({"min_elevation_deg", "max_elevation_deg", "azimuth_centre_deg", "azimuth_half_width_deg",
                       "min_range_m", "max_range_m", "detection_probability", "association_margin_deg",
                       "association_margin_m", "default_camera_position_m"});
  p.min_elevation_rad = deg2rad(n.getDouble("min_elevation_deg", -90.0, 90.0, rad2deg(p.min_elevation_rad)));
  p.max_elevation_rad = deg2rad(n.getDouble("max_elevation_deg", -90.0, 90.0, rad2deg(p.max_elevation_rad)));
  if (p.max_elevation_rad < p.min_elevation_rad)
    throw ConfigError(n.where("max_elevation_deg") + " must be >= min_elevation_deg");
  p.azimuth_centre_rad = deg2rad(n.getDouble("azimuth_centre_deg", -180.0, 180.0, rad2deg(p.azimuth_centre_rad)));
  p.azimuth_half_width_rad =
      deg2rad(n.getDouble("azimuth_half_width_deg", 0.0, 180.0, rad2deg(p.azimuth_half_width_rad), Node::Open::kLow));
  p.min_range_m = n.getDouble("min_range_m", 0.0, 1e6, p.min_range_m);
  if (n.has("max_range_m")) {  // absent: unlimited
    p.max_range_m = n.getDouble("max_range_m", 0.0, 1e6);
    if (p.max_range_m <= p.min_range_m) throw ConfigError(n.where("max_range_m") + " must be > min_range_m");
  }
  p.detection_probability = n.getDouble("detection_probability", 0.0, 1.0, p.detection_probability, Node::Open::kHigh);
  p.association_margin_rad =
      deg2rad(n.getDouble("association_margin_deg", 0.0, 90.0, rad2deg(p.association_margin_rad)));
  p.association_margin_m = n.getDouble("association_margin_m", 0.0, 1e3, p.association_margin_m);
  if (n.has("default_camera_position_m")) {
    const auto v = n.getDoubles("default_camera_position_m", 3, -10.0, 10.0);
    p.default_p_CinR_m = Eigen::Vector3d(v[0], v[1], v[2]);
  }
}

void parseCandidates(const Node& n, slam::CandidateOptions& c) {
  n.rejectUnknownKeys({"nz_min", "ncross_valid", "min_parallax_deg", "require_above_camera",
                       "min_height_above_camera_m", "d_min_m", "initial_cov_diag_m2", "initial_cov_from_triangulation",
                       "refine_initial_point", "refine_iterations", "max_observations", "ray_motion_noise"});
  c.nz_min = static_cast<int>(n.getInt("nz_min", 2, 1000, c.nz_min));
  c.ncross_valid = static_cast<int>(n.getInt("ncross_valid", 1, 100000, c.ncross_valid));
  c.min_parallax_rad = deg2rad(n.getDouble("min_parallax_deg", 0.0, 90.0, rad2deg(c.min_parallax_rad)));
  c.require_above_camera = n.getBool("require_above_camera", c.require_above_camera);
  c.min_height_above_camera_m = n.getDouble("min_height_above_camera_m", 0.0, 100.0, c.min_height_above_camera_m);
  c.d_min_m = n.getDouble("d_min_m", 0.0, 1e4, c.d_min_m);
  if (n.has("initial_cov_diag_m2")) {
    const auto v = n.getDoubles("initial_cov_diag_m2", 3, 1e-12, 1e4);
    c.initial_cov_diag_m2 = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  c.initial_cov_from_triangulation = n.getBool("initial_cov_from_triangulation", c.initial_cov_from_triangulation);
  c.refine_initial_point = n.getBool("refine_initial_point", c.refine_initial_point);
  c.ray_motion_noise = n.getBool("ray_motion_noise", c.ray_motion_noise);
  c.refine_iterations = static_cast<int>(n.getInt("refine_iterations", 0, 100, c.refine_iterations));
  c.max_observations = static_cast<int>(n.getInt("max_observations", 2, 1000, c.max_observations));
}

// An options struct's validate() message starts with the field it names ("proposal needs ...",
// "motion.min_sigma_xy_m must be ..."): reported against that key of the file, like a bad value.
ConfigError validationError(const Node& n, const std::string& err) {
  const auto sp = err.find(' ');
  if (sp == std::string::npos) return ConfigError(n.where("") + " " + err);
  return ConfigError(n.where(err.substr(0, sp)) + err.substr(sp));
}

void parseFilter(const Node& n, slam::FastSlamOptions& f) {
  n.rejectUnknownKeys({"preset", "particles", "association", "proposal", "descriptor_update_rate", "p_new_mahalanobis_sq", "resample_ess_fraction",
                       "inflate_azimuth_near_zenith", "association_predictive", "map_cell_size_m", "odometry_scale_correction", "scale_correction_max_step", "motion",
                       "perception", "candidates"});
  if (n.has("preset")) {  // first: the keys below override the preset's values
    const auto& names = slam::presetNames();
    const std::string preset = n.getEnum("preset", names);
    f = slam::presetOptions(static_cast<slam::Preset>(std::find(names.begin(), names.end(), preset) - names.begin()));
  }
  f.num_particles = static_cast<int>(n.getInt("particles", 1, 100000, f.num_particles));
  f.association = associationFromName(
      n.getEnum("association", associationNames(), associationNames().at(static_cast<std::size_t>(f.association))));
  const std::string proposal =
      n.getEnum("proposal", {"fastslam2", "fastslam1"}, f.proposal == slam::ProposalKind::kFastSlam1 ? "fastslam1" : "fastslam2");
  f.proposal = proposal == "fastslam1" ? slam::ProposalKind::kFastSlam1 : slam::ProposalKind::kFastSlam2;
  f.descriptor_update_rate = n.getDouble("descriptor_update_rate", 1e-6, 1.0, f.descriptor_update_rate);
  f.p_new_mahalanobis_sq = n.getDouble("p_new_mahalanobis_sq", 1e-6, 1e6, f.p_new_mahalanobis_sq);
  f.resample_ess_fraction = n.getDouble("resample_ess_fraction", 0.0, 1.0, f.resample_ess_fraction);
  f.inflate_azimuth_near_zenith = n.getBool("inflate_azimuth_near_zenith", f.inflate_azimuth_near_zenith);
  f.association_predictive = n.getBool("association_predictive", f.association_predictive);
  f.map_cell_size_m = n.getDouble("map_cell_size_m", 0.01, 1e4, f.map_cell_size_m);
  f.odometry_scale_correction = n.getBool("odometry_scale_correction", f.odometry_scale_correction);
  f.scale_correction_max_step = n.getDouble("scale_correction_max_step", 1e-6, 1.0, f.scale_correction_max_step);
  if (auto m = n.optChild("motion")) parseMotion(*m, f.motion);
  if (auto p = n.optChild("perception")) parsePerception(*p, f.perception);
  if (auto c = n.optChild("candidates")) parseCandidates(*c, f.candidates);
  const std::string err = f.validate();
  if (!err.empty()) throw validationError(n, err);
}

void parsePairing(const Node& n, PairingOptions& p) {
  n.rejectUnknownKeys({"max_wait_s", "max_odometry_gap_s", "odometry_buffer_s", "max_pending_frames",
                       "restart_jump_s", "restart_confirm_messages", "max_forward_jump_s", "max_odometry_speed_mps",
                       "max_odometry_yaw_rate_degps"});
  p.max_wait_us = seconds_us(n, "max_wait_s", 0.0, 3600.0, p.max_wait_us);
  p.max_odometry_gap_us = seconds_us(n, "max_odometry_gap_s", 1e-6, 3600.0, p.max_odometry_gap_us);
  p.odometry_buffer_us = seconds_us(n, "odometry_buffer_s", 0.0, 36000.0, p.odometry_buffer_us);
  p.max_pending_frames = static_cast<int>(n.getInt("max_pending_frames", 1, 10000, p.max_pending_frames));
  p.restart_jump_us = seconds_us(n, "restart_jump_s", 1e-6, 1e6, p.restart_jump_us);
  p.restart_confirm_messages =
      static_cast<int>(n.getInt("restart_confirm_messages", 1, 1000, p.restart_confirm_messages));
  p.max_forward_jump_us = seconds_us(n, "max_forward_jump_s", 1e-3, 1e6, p.max_forward_jump_us);
  p.max_odometry_speed_mps = n.getDouble("max_odometry_speed_mps", 1e-3, 1e3, p.max_odometry_speed_mps);
  p.max_odometry_yaw_rate_radps =
      deg2rad(n.getDouble("max_odometry_yaw_rate_degps", 1e-3, 1e5, rad2deg(p.max_odometry_yaw_rate_radps)));
  // The one check across keys, in the file's units (PairingOptions::validate() speaks microseconds).
  if (p.odometry_buffer_us < p.max_wait_us) {
    std::ostringstream msg;
    msg << n.where("odometry_buffer_s") << " must be >= max_wait_s (" << p.max_wait_us * 1e-6 << " s), got "
        << p.odometry_buffer_us * 1e-6 << " s";
    throw ConfigError(msg.str());
  }
  const std::string err = p.validate();
  if (!err.empty()) throw validationError(n, err);
}

void parsePlausibility(const Node& n, PlausibilityOptions& p) {
  n.rejectUnknownKeys({"max_odometry_coordinate_m", "max_odometry_angle_rad", "max_camera_offset_m", "jump_confirm_messages"});
  p.max_odometry_coordinate_m = n.getDouble("max_odometry_coordinate_m", 1.0, 1e9, p.max_odometry_coordinate_m);
  p.max_odometry_angle_rad = n.getDouble("max_odometry_angle_rad", 4.0, 1e9, p.max_odometry_angle_rad);
  p.max_camera_offset_m = n.getDouble("max_camera_offset_m", 0.01, 1e3, p.max_camera_offset_m);
  p.jump_confirm_messages = static_cast<int>(n.getInt("jump_confirm_messages", 1, 1000, p.jump_confirm_messages));
}

void parseRestart(const Node& n, RestartOptions& r) {
  n.rejectUnknownKeys({"reinit_from", "position_sigma_m", "heading_sigma_deg"});
  const std::string from = n.getEnum("reinit_from", {"last_estimate", "start_pose"}, "last_estimate");
  r.reinit_from = from == "start_pose" ? RestartOptions::ReinitFrom::kStartPose : RestartOptions::ReinitFrom::kLastEstimate;
  r.position_sigma_m = n.getDouble("position_sigma_m", 0.0, 1e3, r.position_sigma_m);
  r.heading_sigma_rad = deg2rad(n.getDouble("heading_sigma_deg", 0.0, 180.0, rad2deg(r.heading_sigma_rad)));
}

}  // namespace

std::string SlamProcessOptions::validate() const {
  const std::string f = filter.validate();
  if (!f.empty()) return "filter: " + f;
  const std::string p = pairing.validate();
  if (!p.empty()) return "pairing: " + p;
  if (map_every_n_frames < 1) return "map_every_n_frames must be >= 1";
  if (max_features_per_frame < 1 || max_features_per_frame > 4096) return "features.max_per_frame must be in [1, 4096]";
  if (odometry_only_after_us < 0) return "output.odometry_only_after_s must be >= 0";
  if (odometry_only_period_us <= 0) return "output.odometry_only_period_s must be > 0";
  if (localisation_only && load_map_path.empty()) return "map.localisation_only needs map.load_path (a map to localise in)";
  if (!use_ceiling_lights && !use_vertical_lines) return "at least one feature kind must be used";
  if (checkpoint_interval_us < 1000 || checkpoint_interval_us > 1'000'000'000'000)
    return "checkpoint.interval_s must be in [0.001, 1e6]";
  if (!(plausibility.max_odometry_coordinate_m > 0) || !(plausibility.max_odometry_angle_rad > 0) ||
      !(plausibility.max_camera_offset_m > 0) || plausibility.jump_confirm_messages < 1)
    return "plausibility: bounds must be > 0 and jump_confirm_messages >= 1";
  if (!(restart.position_sigma_m >= 0) || !(restart.heading_sigma_rad >= 0))
    return "restart: position_sigma_m and heading_sigma_deg must be >= 0";
  return "";
}

SlamProcessOptions parseSlamOptions(const Node& root) {
  root.rejectUnknownKeys(
      {"seed", "start_pose", "features", "output", "pairing", "filter", "map", "checkpoint", "plausibility", "restart"});
  SlamProcessOptions o;
  o.seed = static_cast<std::uint64_t>(root.getInt("seed", 0, INT64_MAX, 1));
  if (auto s = root.optChild("start_pose")) {
    s->rejectUnknownKeys({"source", "x_m", "y_m", "theta_deg"});
    const std::string src = s->getEnum("source", {"odometry", "fixed"});
    if (src == "fixed") {
      o.start_source = SlamProcessOptions::StartSource::kFixed;
      o.start_pose_W = Pose2{s->getDouble("x_m", -1e6, 1e6), s->getDouble("y_m", -1e6, 1e6),
                             wrapAngle(deg2rad(s->getDouble("theta_deg", -360.0, 360.0)))};
    }
  }
  if (auto f = root.optChild("features")) {
    f->rejectUnknownKeys({"use_ceiling_lights", "use_vertical_lines", "min_sigma_deg", "max_per_frame"});
    o.min_sigma_rad = deg2rad(f->getDouble("min_sigma_deg", 0.0, 90.0, 0.0));
    o.max_features_per_frame = static_cast<int>(f->getInt("max_per_frame", 1, 4096, o.max_features_per_frame));
    o.use_ceiling_lights = f->getBool("use_ceiling_lights", o.use_ceiling_lights);
    o.use_vertical_lines = f->getBool("use_vertical_lines", o.use_vertical_lines);
    if (!o.use_ceiling_lights && !o.use_vertical_lines)
      throw ConfigError(f->where("use_ceiling_lights") + " and use_vertical_lines cannot both be false");
  }
  if (auto out = root.optChild("output")) {
    out->rejectUnknownKeys({"map_every_n_frames", "odometry_only_after_s", "odometry_only_period_s"});
    o.map_every_n_frames = static_cast<int>(out->getInt("map_every_n_frames", 1, 1000000, 1));
    o.odometry_only_after_us = seconds_us(*out, "odometry_only_after_s", 0.0, 3600.0, o.odometry_only_after_us);
    o.odometry_only_period_us = seconds_us(*out, "odometry_only_period_s", 0.01, 3600.0, o.odometry_only_period_us);
  }
  if (auto m = root.optChild("map")) {
    m->rejectUnknownKeys({"save_path", "load_path", "localisation_only"});
    if (m->has("save_path")) o.save_map_path = m->getPath("save_path");
    if (m->has("load_path")) o.load_map_path = m->getPath("load_path");
    o.localisation_only = m->getBool("localisation_only", false);
    if (o.localisation_only && o.load_map_path.empty())
      throw ConfigError(m->where("localisation_only") + " needs map.load_path (a map to localise in)");
  }
  if (auto c = root.optChild("checkpoint")) {
    c->rejectUnknownKeys({"path", "interval_s"});
    if (c->has("path")) o.checkpoint_path = c->getPath("path");
    o.checkpoint_interval_us = seconds_us(*c, "interval_s", 0.001, 1e6, o.checkpoint_interval_us);
  }
  if (auto p = root.optChild("pairing")) parsePairing(*p, o.pairing);
  if (auto p = root.optChild("plausibility")) parsePlausibility(*p, o.plausibility);
  if (auto r = root.optChild("restart")) parseRestart(*r, o.restart);
  if (auto f = root.optChild("filter")) parseFilter(*f, o.filter);
  return o;
}

const std::vector<std::string>& associationNames() {
  static const std::vector<std::string> names{"hungarian", "ml"};  // index = AssociationMethod
  return names;
}

slam::AssociationMethod associationFromName(const std::string& name) {
  const auto& names = associationNames();
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) throw std::invalid_argument("unknown association method '" + name + "'");
  return static_cast<slam::AssociationMethod>(it - names.begin());
}

SlamProcessOptions loadSlamOptions(const std::string& path) { return parseSlamOptions(Node::loadFile(path)); }

SlamProcessOptions loadSlamOptions(const std::string& path, const std::vector<std::string>& overrides) {
  return parseSlamOptions(Node::loadFileWithOverrides(path, overrides));
}

std::string describe(const SlamProcessOptions& o) {
  std::ostringstream s;
  const auto& f = o.filter;
  s << "filter: " << f.num_particles << " particles, "
    << (f.proposal == slam::ProposalKind::kFastSlam2 ? "FastSLAM 2.0" : "FastSLAM 1.0") << ", association "
    << associationNames().at(static_cast<std::size_t>(f.association));
  s << ", motion noise "
    << (f.motion.model == slam::MotionNoiseModel::kChord ? "chord" : "translate-then-rotate") << ", P_new at Mahalanobis^2 "
    << f.p_new_mahalanobis_sq << ", NZ_min " << f.candidates.nz_min << ", NCROSS_valid " << f.candidates.ncross_valid
    << ", ANG_min " << rad2deg(f.candidates.min_parallax_rad) << " deg, D_min " << f.candidates.d_min_m
    << " m, p_in " << f.perception.detection_probability << ", seed " << o.seed << "\n";
  const std::vector<std::string> deviations = slam::presetDeviations(f);
  s << "deviations from paper 000: ";
  for (std::size_t i = 0; i < deviations.size(); ++i) s << (i ? ", " : "") << deviations[i];
  s << (deviations.empty() ? "none\n" : "\n");
  s << "pairing: max_wait " << o.pairing.max_wait_us * 1e-6 << " s, max odometry gap "
    << o.pairing.max_odometry_gap_us * 1e-6 << " s, buffer " << o.pairing.odometry_buffer_us * 1e-6
    << " s, max pending " << o.pairing.max_pending_frames << ", restart jump " << o.pairing.restart_jump_us * 1e-6
    << " s, max jump ahead " << o.pairing.max_forward_jump_us * 1e-6 << " s; a restart re-initialises from "
    << (o.restart.reinit_from == RestartOptions::ReinitFrom::kLastEstimate
            ? "the last estimate (+" + std::to_string(o.restart.position_sigma_m) + " m, +" +
                  std::to_string(rad2deg(o.restart.heading_sigma_rad)) + " deg)"
            : std::string("the start pose"))
    << "\n";
  s << "start: " << (o.start_source == SlamProcessOptions::StartSource::kOdometry ? "odometry frame" : "fixed (")
    << (o.start_source == SlamProcessOptions::StartSource::kFixed
            ? std::to_string(o.start_pose_W.x_m) + ", " + std::to_string(o.start_pose_W.y_m) + ", " +
                  std::to_string(o.start_pose_W.theta_rad) + " rad)"
            : "")
    << "; features: ceiling lights " << (o.use_ceiling_lights ? "on" : "off") << ", vertical lines "
    << (o.use_vertical_lines ? "on" : "off") << ", sigma floor " << rad2deg(o.min_sigma_rad) << " deg; SLAM_MAP every "
    << o.map_every_n_frames << " frame(s)";
  if (!o.load_map_path.empty())
    s << "\nmap: start from " << o.load_map_path << (o.localisation_only ? " (localisation only: fixed)" : " (updated)");
  if (!o.save_map_path.empty()) s << (o.load_map_path.empty() ? "\n" : "; ") << "map: saved to " << o.save_map_path << " on exit";
  return s.str();
}

}  // namespace omnislam::slamproc
