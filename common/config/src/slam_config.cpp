// SLAM process config parsing: see slam_config.h and docs/user/slam-process.md.
#include "omnislam/config/slam_config.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>

#include "omnislam/core/angles.h"
#include "omnislam/core/slam/options_table.h"

namespace omnislam::slamproc {

namespace {

using config::ConfigError;
using config::Node;

int64_t seconds_us(const Node& n, const std::string& key, double lo, double hi, int64_t def_us) {
  return static_cast<int64_t>(std::llround(n.getDouble(key, lo, hi, static_cast<double>(def_us) * 1e-6) * 1e6));
}

Node::Open openOf(slam::options::Bounds b) {
  return b == slam::options::Bounds::kLowOpen    ? Node::Open::kLow
         : b == slam::options::Bounds::kHighOpen ? Node::Open::kHigh
                                                 : Node::Open::kNone;
}

// The keys of one options table given in section n, each read within its range and converted to
// the member's units; a key not given keeps the member's value (the preset's or the default).
template <class S>
void parseFields(const Node& n, S& s, const std::vector<slam::options::Field<S>>& table) {
  using slam::options::Kind;
  for (const auto& f : table) {
    if (!n.has(f.key)) continue;
    switch (f.kind) {
      case Kind::kReal: {
        const double v = n.getDouble(f.key, f.lo, f.hi, openOf(f.bounds));
        s.*f.real = f.degrees ? deg2rad(v) : v;
        break;
      }
      case Kind::kInt:
        s.*f.integer = static_cast<int>(n.getInt(f.key, static_cast<int64_t>(f.lo), static_cast<int64_t>(f.hi)));
        break;
      case Kind::kBool: s.*f.flag = n.getBool(f.key); break;
      case Kind::kVec3: {
        const auto v = n.getDoubles(f.key, 3, f.lo, f.hi);
        s.*f.vec3 = Eigen::Vector3d(v[0], v[1], v[2]);
        break;
      }
      case Kind::kEnum: {
        const std::string v = n.getEnum(f.key, *f.names);
        f.set_index(s, static_cast<int>(std::find(f.names->begin(), f.names->end(), v) - f.names->begin()));
        break;
      }
    }
  }
}

// The keys a section accepts: its table's and the names of its subsections.
template <class S>
std::vector<std::string> keysOf(const std::vector<slam::options::Field<S>>& table,
                                std::vector<std::string> extra = {}) {
  for (const auto& f : table) extra.emplace_back(f.key);
  return extra;
}

void parsePerception(const Node& n, slam::PerceptionOptions& p) {
  n.rejectUnknownKeysIn(keysOf(slam::options::perceptionFields()));
  parseFields(n, p, slam::options::perceptionFields());
  if (p.max_elevation_rad < p.min_elevation_rad)
    throw ConfigError(n.where("max_elevation_deg") + " must be >= min_elevation_deg");
  if (p.max_range_m <= p.min_range_m) throw ConfigError(n.where("max_range_m") + " must be > min_range_m");
}

// An options struct's validate() message starts with the field it names ("proposal needs ...",
// "motion.min_sigma_xy_m must be ..."): reported against that key of the file, like a bad value.
ConfigError validationError(const Node& n, const std::string& err) {
  const auto sp = err.find(' ');
  if (sp == std::string::npos) return ConfigError(n.where("") + " " + err);
  return ConfigError(n.where(err.substr(0, sp)) + err.substr(sp));
}

void parseFilter(const Node& n, slam::FastSlamOptions& f) {
  namespace opt = slam::options;
  n.rejectUnknownKeysIn(keysOf(opt::fastSlamFields(), {"preset", "motion", "perception", "candidates", "keyframes"}));
  if (n.has("preset")) {  // first: the keys given override the preset's values
    const auto& names = slam::presetNames();
    const std::string preset = n.getEnum("preset", names);
    f = slam::presetOptions(static_cast<slam::Preset>(std::find(names.begin(), names.end(), preset) - names.begin()));
  }
  parseFields(n, f, opt::fastSlamFields());
  if (auto m = n.optChild("motion")) {
    m->rejectUnknownKeysIn(keysOf(opt::motionFields()));
    parseFields(*m, f.motion, opt::motionFields());
  }
  if (auto p = n.optChild("perception")) parsePerception(*p, f.perception);
  if (auto c = n.optChild("candidates")) {
    c->rejectUnknownKeysIn(keysOf(opt::candidateFields()));
    parseFields(*c, f.candidates, opt::candidateFields());
  }
  if (auto k = n.optChild("keyframes")) {
    k->rejectUnknownKeysIn(keysOf(opt::keyframeFields()));
    parseFields(*k, f.keyframes, opt::keyframeFields());
  }
  const std::string err = f.validate();
  if (!err.empty()) throw validationError(n, err);
}

void parsePairing(const Node& n, PairingOptions& p) {
  n.rejectUnknownKeys({"max_wait_s", "max_odometry_gap_s", "odometry_buffer_s", "max_pending_frames", "restart_jump_s",
                       "restart_confirm_messages", "max_forward_jump_s", "max_odometry_speed_mps",
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
  n.rejectUnknownKeys(
      {"max_odometry_coordinate_m", "max_odometry_angle_rad", "max_camera_offset_m", "jump_confirm_messages"});
  p.max_odometry_coordinate_m = n.getDouble("max_odometry_coordinate_m", 1.0, 1e9, p.max_odometry_coordinate_m);
  p.max_odometry_angle_rad = n.getDouble("max_odometry_angle_rad", 4.0, 1e9, p.max_odometry_angle_rad);
  p.max_camera_offset_m = n.getDouble("max_camera_offset_m", 0.01, 1e3, p.max_camera_offset_m);
  p.jump_confirm_messages = static_cast<int>(n.getInt("jump_confirm_messages", 1, 1000, p.jump_confirm_messages));
}

void parseRestart(const Node& n, RestartOptions& r) {
  n.rejectUnknownKeys({"reinit_from", "position_sigma_m", "heading_sigma_deg"});
  const std::string from = n.getEnum("reinit_from", {"last_estimate", "start_pose"}, "last_estimate");
  r.reinit_from =
      from == "start_pose" ? RestartOptions::ReinitFrom::kStartPose : RestartOptions::ReinitFrom::kLastEstimate;
  r.position_sigma_m = n.getDouble("position_sigma_m", 0.0, 1e3, r.position_sigma_m);
  r.heading_sigma_rad = deg2rad(n.getDouble("heading_sigma_deg", 0.0, 180.0, rad2deg(r.heading_sigma_rad)));
}

}  // namespace

std::string SlamProcessOptions::validate() const {
  const std::string f = filter.validate();
  if (!f.empty()) return "filter: " + f;
  const std::string p = pairing.validate();
  if (!p.empty()) return "pairing: " + p;
  if (const std::string h = health.validate(); !h.empty()) return "health: " + h;
  if (map_every_n_frames < 1) return "map_every_n_frames must be >= 1";
  if (max_features_per_frame < 1 || max_features_per_frame > 4096) return "features.max_per_frame must be in [1, 4096]";
  if (odometry_only_after_us < 0) return "output.odometry_only_after_s must be >= 0";
  if (odometry_only_period_us <= 0) return "output.odometry_only_period_s must be > 0";
  if (localisation_only && load_map_path.empty())
    return "map.localisation_only needs map.load_path (a map to localise in)";
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
  root.rejectUnknownKeys({"seed", "start_pose", "features", "output", "pairing", "filter", "map", "checkpoint",
                          "plausibility", "restart", "health"});
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
  if (auto h = root.optChild("health")) {
    h->rejectUnknownKeysIn(keysOf(slam::options::healthFields()));
    parseFields(*h, o.health, slam::options::healthFields());
  }
  return o;
}

const std::vector<std::string>& associationNames() { return slam::options::associationNames(); }

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
  namespace opt = slam::options;
  s << "filter: " << opt::describeFields(f, opt::fastSlamFields()) << "; seed " << o.seed << "\n";
  s << "filter.motion: " << opt::describeFields(f.motion, opt::motionFields()) << "\n";
  s << "filter.perception: " << opt::describeFields(f.perception, opt::perceptionFields()) << "\n";
  s << "filter.candidates: " << opt::describeFields(f.candidates, opt::candidateFields()) << "\n";
  s << "filter.keyframes: " << opt::describeFields(f.keyframes, opt::keyframeFields()) << "\n";
  s << "health: " << opt::describeFields(o.health, opt::healthFields()) << "\n";
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
    s << "\nmap: start from " << o.load_map_path
      << (o.localisation_only ? " (localisation only: fixed)" : " (updated)");
  if (!o.save_map_path.empty())
    s << (o.load_map_path.empty() ? "\n" : "; ") << "map: saved to " << o.save_map_path << " on exit";
  return s.str();
}

namespace {

template <class S>
void markdownRows(std::ostringstream& s, const std::string& section,
                  const std::vector<slam::options::Field<S>>& table) {
  const S defaults{};
  for (const auto& f : table) {
    s << "| `" << section << f.key << "` | `" << f.field << "` | " << f.unit << " | " << slam::options::rangeText(f)
      << " | " << slam::options::valueText(f, defaults) << " | " << f.doc << " |\n";
  }
}

}  // namespace

std::string filterKeysMarkdown() {
  namespace opt = slam::options;
  std::ostringstream s;
  s << "| key | field | unit | range | default | meaning |\n|---|---|---|---|---|---|\n";
  s << "| `filter.preset` | - | | " <<
      [] {
        std::string n;
        for (const auto& p : slam::presetNames()) n += (n.empty() ? "" : ", ") + p;
        return n;
      }()
    << " | none (= recommended) | every key below at once; keys given beside it override it |\n";
  markdownRows(s, "filter.", opt::fastSlamFields());
  markdownRows(s, "filter.motion.", opt::motionFields());
  markdownRows(s, "filter.perception.", opt::perceptionFields());
  markdownRows(s, "filter.candidates.", opt::candidateFields());
  markdownRows(s, "filter.keyframes.", opt::keyframeFields());
  markdownRows(s, "health.", opt::healthFields());
  return s.str();
}

}  // namespace omnislam::slamproc
