// The tables of the SLAM process's own keys (see slam_options_table.h): one row per key; the
// defaults are the structs' in-class values (slam_config.h), the ranges the accepted ones.
#include "omnislam/runtime/slam_options_table.h"

#include <sstream>

#include "omnislam/core/slam/options_table.h"
#include "omnislam/runtime/pairing_options_table.h"
#include "omnislam/smoothing/back_end_options_table.h"

namespace omnislam::runtime {

namespace {

using options::Bounds;
using options::enumeration;
using options::flag;
using options::integer;
using options::path;
using options::real;
using options::realVia;
using options::seconds;
using options::uint64;
using O = SlamProcessOptions;
constexpr Bounds kC = Bounds::kClosed;
constexpr double kInt64Max = 9223372036854775807.0;  // the seed's range: that of --seed

}  // namespace

const std::vector<std::string>& startSourceNames() {
  static const std::vector<std::string> n{"odometry", "fixed", "unknown"};
  return n;
}
const std::vector<std::string>& reinitFromNames() {
  static const std::vector<std::string> n{"last_estimate", "start_pose"};
  return n;
}

// One row per key: not reformatted.
// clang-format off
const std::vector<ProcessField>& topLevelFields() {
  static const std::vector<ProcessField> t{
      uint64<O>("seed", &O::seed, "seed", 0, kInt64Max, "the filter's random seed (--seed overrides); same input and seed, same output"),
  };
  return t;
}

const std::vector<ProcessField>& startPoseFields() {
  static const std::vector<ProcessField> t{
      enumeration<O>("source", "start_source", startSourceNames(), [](const O& o) { return static_cast<int>(o.start_source); },
                     [](O& o, int i) { o.start_source = static_cast<O::StartSource>(i); },
                     "odometry: the map frame is the odometry frame; fixed: x_m, y_m, theta_deg is the robot's pose at the first frame (required in the section); unknown: found by global localisation in the loaded map (needs map.load_path; no SLAM_POSE until localised, localisation.*)"),
      realVia<O>("x_m", [](const O& o) { return o.start_pose_W.x_m; }, [](O& o, double v) { o.start_pose_W.x_m = v; },
                 "start_pose_W.x_m", "m", -1e6, 1e6, kC, "with source fixed (required there; not read with odometry or unknown): x of the start pose in W"),
      realVia<O>("y_m", [](const O& o) { return o.start_pose_W.y_m; }, [](O& o, double v) { o.start_pose_W.y_m = v; },
                 "start_pose_W.y_m", "m", -1e6, 1e6, kC, "with source fixed (required there; not read with odometry or unknown): y of the start pose in W"),
      realVia<O>("theta_deg", [](const O& o) { return o.start_pose_W.theta_rad; }, [](O& o, double v) { o.start_pose_W.theta_rad = wrapAngle(v); },
                 "start_pose_W.theta_rad", "deg", -360, 360, kC, "with source fixed (required there; not read with odometry or unknown): heading of the start pose in W (wrapped)", true),
  };
  return t;
}

const std::vector<ProcessField>& featureFields() {
  static const std::vector<ProcessField> t{
      flag<O>("use_ceiling_lights", &O::use_ceiling_lights, "use_ceiling_lights", "ceiling lights are used (not both kinds off)"),
      flag<O>("use_vertical_lines", &O::use_vertical_lines, "use_vertical_lines", "vertical lines are used"),
      real<O>("min_sigma_deg", &O::min_sigma_rad, "min_sigma_rad", "deg", 0, 90, kC, "floor on each angle's standard deviation (0: the covariance as published)", true),
      integer<O>("max_per_frame", &O::max_features_per_frame, "max_features_per_frame", 1, 4096, "a frame with more usable features is refused whole and counted (too_large)"),
  };
  return t;
}

const std::vector<ProcessField>& outputFields() {
  static const std::vector<ProcessField> t{
      integer<O>("map_every_n_frames", &O::map_every_n_frames, "map_every_n_frames", 1, 1e6, "SLAM_MAP on every n-th processed frame (SLAM_POSE, SLAM_PARTICLES on every one)"),
      seconds<O>("odometry_only_after_s", &O::odometry_only_after_us, "odometry_only_after_us", 0, 3600, "odometry-only poses when no frame came for this long (0 = off)"),
      seconds<O>("odometry_only_period_s", &O::odometry_only_period_us, "odometry_only_period_us", 0.01, 3600, "the period of the odometry-only poses"),
  };
  return t;
}

const std::vector<ProcessField>& mapFields() {
  static const std::vector<ProcessField> t{
      path<O>("save_path", &O::save_map_path, "save_map_path", "the best particle's map written here on exit (\"\" = not saved; --save-map overrides)"),
      path<O>("load_path", &O::load_map_path, "load_map_path", "the filter starts from this map (\"\" = none; --load-map overrides)"),
      flag<O>("localisation_only", &O::localisation_only, "localisation_only", "the loaded map stays fixed (needs load_path; --localise)"),
  };
  return t;
}

const std::vector<ProcessField>& checkpointFields() {
  static const std::vector<ProcessField> t{
      path<O>("path", &O::checkpoint_path, "checkpoint_path", "the checkpoint file (\"\" = off; --checkpoint overrides)"),
      seconds<O>("interval_s", &O::checkpoint_interval_us, "checkpoint_interval_us", 0.001, 1e6, "data time between two checkpoints (--checkpoint-interval overrides)"),
  };
  return t;
}

const std::vector<options::Field<PlausibilityOptions>>& plausibilityFields() {
  using P = PlausibilityOptions;
  static const std::vector<options::Field<P>> t{
      real<P>("max_odometry_coordinate_m", &P::max_odometry_coordinate_m, "max_odometry_coordinate_m", "m", 1, 1e9, kC, "an ODOMETRY pose with x or y beyond +-this is refused (the workspace)"),
      real<P>("max_odometry_angle_rad", &P::max_odometry_angle_rad, "max_odometry_angle_rad", "rad", 4, 1e9, kC, "an ODOMETRY pose with theta beyond +-this (wrapped or not) is refused"),
      real<P>("max_camera_offset_m", &P::max_camera_offset_m, "max_camera_offset_m", "m", 0.01, 1e3, kC, "OMNI_FEATURES with a camera_position_m longer than this is refused"),
      integer<P>("jump_confirm_messages", &P::jump_confirm_messages, "jump_confirm_messages", 1, 1000, "rule 3: odometry poses in a row that confirm a jump"),
  };
  return t;
}

const std::vector<options::Field<RestartOptions>>& restartFields() {
  using R = RestartOptions;
  static const std::vector<options::Field<R>> t{
      enumeration<R>("reinit_from", "reinit_from", reinitFromNames(), [](const R& r) { return static_cast<int>(r.reinit_from); },
                     [](R& r, int i) { r.reinit_from = static_cast<R::ReinitFrom>(i); },
                     "after a restart of the inputs: the last estimate (widened) or the start pose with an empty map"),
      real<R>("position_sigma_m", &R::position_sigma_m, "position_sigma_m", "m", 0, 1e3, kC, "last_estimate: added position standard deviation"),
      real<R>("heading_sigma_deg", &R::heading_sigma_rad, "heading_sigma_rad", "deg", 0, 180, kC, "last_estimate: added heading standard deviation", true),
  };
  return t;
}
// clang-format on

namespace {

// Text as one Markdown table cell: a '|' would end the cell.
std::string cell(const std::string& text) {
  std::string out;
  for (const char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

// A section over the part of SlamProcessOptions that `part` returns.
template <class S>
ConfigSection section(std::string name, const std::vector<options::Field<S>>& (*table)(),
                      const S& (*part)(const SlamProcessOptions&), bool of_the_run = false) {
  ConfigSection c;
  c.name = name;
  c.of_the_run = of_the_run;
  c.describe = [table, part](const SlamProcessOptions& o) { return options::describeFields(part(o), table()); };
  c.check = [table, part](const SlamProcessOptions& o) { return options::checkRanges(part(o), table()); };
  c.markdownRows = [name, table, part] {
    const SlamProcessOptions defaults{};
    const std::string prefix = name.empty() ? "" : name + ".";
    std::ostringstream s;
    for (const auto& f : table()) {
      s << "| `" << prefix << f.key << "` | `" << f.field << "` | " << f.unit << " | " << options::rangeText(f) << " | "
        << options::valueText(f, part(defaults)) << " | " << cell(f.doc) << " |\n";
    }
    return s.str();
  };
  return c;
}

const SlamProcessOptions& whole(const SlamProcessOptions& o) { return o; }

}  // namespace

const std::vector<ConfigSection>& filterSections() {
  namespace opt = slam::options;
  static const std::vector<ConfigSection> s{
      section<slam::FastSlamOptions>(
          "filter", opt::fastSlamFields, [](const O& o) -> const auto& { return o.filter; }),
      section<slam::MotionNoiseOptions>(
          "filter.motion", opt::motionFields, [](const O& o) -> const auto& { return o.filter.motion; }),
      section<slam::PerceptionOptions>(
          "filter.perception", opt::perceptionFields, [](const O& o) -> const auto& { return o.filter.perception; }),
      section<slam::CandidateOptions>(
          "filter.candidates", opt::candidateFields, [](const O& o) -> const auto& { return o.filter.candidates; }),
      section<slam::KeyframeOptions>(
          "filter.keyframes", opt::keyframeFields, [](const O& o) -> const auto& { return o.filter.keyframes; }),
  };
  return s;
}

const std::vector<ConfigSection>& processSections() {
  static const std::vector<ConfigSection> s{
      section<O>("", topLevelFields, whole),
      section<O>("start_pose", startPoseFields, whole),
      section<slam::GlobalLocalisationOptions>(
          "localisation", slam::options::globalLocalisationFields,
          [](const O& o) -> const auto& { return o.localisation; }),
      section<slam::LostOptions>(
          "lost", slam::options::lostFields, [](const O& o) -> const auto& { return o.lost; }),
      section<O>("features", featureFields, whole),
      section<O>("output", outputFields, whole),
      section<O>("map", mapFields, whole, true),
      section<O>("checkpoint", checkpointFields, whole, true),
      section<PairingOptions>(
          "pairing", pairingFields, [](const O& o) -> const auto& { return o.pairing; }),
      section<RestartOptions>(
          "restart", restartFields, [](const O& o) -> const auto& { return o.restart; }),
      section<PlausibilityOptions>(
          "plausibility", plausibilityFields, [](const O& o) -> const auto& { return o.plausibility; }),
      section<slam::HealthOptions>(
          "health", slam::options::healthFields, [](const O& o) -> const auto& { return o.health; }),
      section<smoothing::BackEndOptions>(
          "backend", smoothing::backEndFields, [](const O& o) -> const auto& { return o.backend; }),
      section<smoothing::SolverOptions>(
          "backend.solver", smoothing::solverFields, [](const O& o) -> const auto& { return o.backend.solver; }),
  };
  return s;
}

}  // namespace omnislam::runtime
