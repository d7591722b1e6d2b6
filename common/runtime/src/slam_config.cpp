// SLAM process config parsing: see slam_config.h and docs/user/slam-process.md. Every key is read
// through its options table (slam_options_table.h, the core's options_table.h, pairing_options_table.h).
#include "omnislam/runtime/slam_config.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>

#include "omnislam/config/options_parse.h"
#include "omnislam/runtime/slam_options_table.h"
#include "omnislam/core/angles.h"
#include "omnislam/core/slam/options_table.h"
#include "omnislam/smoothing/back_end_options_table.h"
#include "omnislam/runtime/pairing_options_table.h"

namespace omnislam::runtime {

namespace {

using config::ConfigError;
using config::Node;
using options::Kind;

using config::keysOf;
using config::parseField;
using config::parseFields;
using config::parseSection;

void parsePerception(const Node& n, slam::PerceptionOptions& p) {
  parseSection(n, p, slam::options::perceptionFields());
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
  if (auto m = n.optChild("motion")) parseSection(*m, f.motion, opt::motionFields());
  if (auto p = n.optChild("perception")) parsePerception(*p, f.perception);
  if (auto c = n.optChild("candidates")) parseSection(*c, f.candidates, opt::candidateFields());
  if (auto k = n.optChild("keyframes")) parseSection(*k, f.keyframes, opt::keyframeFields());
  const std::string err = f.validate();
  if (!err.empty()) throw validationError(n, err);
}

void parseBackEnd(const Node& n, smoothing::BackEndOptions& b) {
  n.rejectUnknownKeysIn(keysOf(smoothing::backEndFields(), {"solver"}));
  parseFields(n, b, smoothing::backEndFields());
  if (auto s = n.optChild("solver")) parseSection(*s, b.solver, smoothing::solverFields());
  const std::string err = b.validate();
  if (!err.empty()) throw validationError(n, err);
}

void parsePairing(const Node& n, PairingOptions& p) {
  parseSection(n, p, pairingFields());
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

// Given, the section needs its source; the pose keys are required with source fixed and not read
// with odometry.
void parseStartPose(const Node& n, SlamProcessOptions& o) {
  const auto& table = startPoseFields();
  n.rejectUnknownKeysIn(keysOf(table));
  for (const auto& f : table) {
    if (f.kind == Kind::kEnum) parseField(n, o, f);
  }
  if (o.start_source != SlamProcessOptions::StartSource::kFixed) return;
  for (const auto& f : table) {
    if (f.kind != Kind::kEnum) parseField(n, o, f);
  }
}

void parseLocalisation(const Node& n, slam::GlobalLocalisationOptions& g) {
  parseSection(n, g, slam::options::globalLocalisationFields());
  const std::string err = g.validate();  // the checks across keys
  if (!err.empty()) throw validationError(n, err);
}

void parseFeatures(const Node& n, SlamProcessOptions& o) {
  parseSection(n, o, featureFields());
  if (!o.use_ceiling_lights && !o.use_vertical_lines)
    throw ConfigError(n.where("use_ceiling_lights") + " and use_vertical_lines cannot both be false");
}

void parseMap(const Node& n, SlamProcessOptions& o) {
  parseSection(n, o, mapFields());
  if (o.localisation_only && o.load_map_path.empty())
    throw ConfigError(n.where("localisation_only") + " needs map.load_path (a map to localise in)");
}

}  // namespace

std::string SlamProcessOptions::validate() const {
  const std::string f = filter.validate();
  if (!f.empty()) return "filter: " + f;
  const std::string p = pairing.validate();
  if (!p.empty()) return "pairing: " + p;
  for (const auto& section : processSections()) {
    const std::string err = section.check(*this);  // the tables' ranges
    if (!err.empty()) return (section.name.empty() ? "" : section.name + ": ") + err;
  }
  if (const std::string b = backend.validate(); !b.empty()) return "backend: " + b;
  if (!use_ceiling_lights && !use_vertical_lines) return "at least one feature kind must be used";
  if (localisation_only && load_map_path.empty())
    return "map.localisation_only needs map.load_path (a map to localise in)";
  if (const std::string g = localisation.validate(); !g.empty()) return "localisation: " + g;
  if (start_source == StartSource::kUnknown && load_map_path.empty())
    return "start_pose.source unknown needs map.load_path or --load-map (a saved map to localise in)";
  return "";
}

SlamProcessOptions parseSlamOptions(const Node& root) {
  std::vector<std::string> known = keysOf(topLevelFields());  // seed and the names of the sections
  for (const auto& section : processSections())
    if (!section.name.empty()) known.push_back(section.name);
  known.emplace_back("filter");
  root.rejectUnknownKeysIn(known);
  SlamProcessOptions o;
  parseFields(root, o, topLevelFields());
  if (auto s = root.optChild("start_pose")) parseStartPose(*s, o);
  if (auto l = root.optChild("localisation")) parseLocalisation(*l, o.localisation);
  if (auto l = root.optChild("lost")) parseSection(*l, o.lost, slam::options::lostFields());
  if (auto f = root.optChild("features")) parseFeatures(*f, o);
  if (auto out = root.optChild("output")) parseSection(*out, o, outputFields());
  if (auto m = root.optChild("map")) parseMap(*m, o);
  if (auto c = root.optChild("checkpoint")) parseSection(*c, o, checkpointFields());
  if (auto p = root.optChild("pairing")) parsePairing(*p, o.pairing);
  if (auto p = root.optChild("plausibility")) parseSection(*p, o.plausibility, plausibilityFields());
  if (auto r = root.optChild("restart")) parseSection(*r, o.restart, restartFields());
  if (auto f = root.optChild("filter")) parseFilter(*f, o.filter);
  if (auto h = root.optChild("health")) parseSection(*h, o.health, slam::options::healthFields());
  if (auto b = root.optChild("backend")) parseBackEnd(*b, o.backend);
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
  for (const auto& section : filterSections()) s << section.name << ": " << section.describe(o) << "\n";
  const std::vector<std::string> deviations = slam::presetDeviations(o.filter);
  s << "deviations from paper 000: ";
  for (std::size_t i = 0; i < deviations.size(); ++i) s << (i ? ", " : "") << deviations[i];
  s << (deviations.empty() ? "none" : "");
  std::string run_files;  // the sections of one run's files, on the last line
  for (const auto& section : processSections()) {
    const std::string line = (section.name.empty() ? "" : section.name + ": ") + section.describe(o);
    if (section.of_the_run) run_files += (run_files.empty() ? "" : "; ") + line;
    else s << "\n" << line;
  }
  if (!run_files.empty()) s << "\n" << run_files;
  return s.str();
}

namespace {

const char* const kMarkdownHeader = "| key | field | unit | range | default | meaning |\n|---|---|---|---|---|---|\n";

}  // namespace

std::string filterKeysMarkdown() {
  std::ostringstream s;
  s << kMarkdownHeader << "| `filter.preset` | - | | " <<
      [] {
        std::string n;
        for (const auto& p : slam::presetNames()) n += (n.empty() ? "" : ", ") + p;
        return n;
      }()
    << " | none (= recommended) | every key below at once; keys given beside it override it |\n";
  for (const auto& section : filterSections()) s << section.markdownRows();
  return s.str();
}

std::string processKeysMarkdown() {
  std::string s = kMarkdownHeader;
  for (const auto& section : processSections()) s += section.markdownRows();
  return s;
}

}  // namespace omnislam::runtime
