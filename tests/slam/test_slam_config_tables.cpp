// The options tables of the SLAM config's own sections (omnislam/runtime/slam_options_table.h and the
// pairing's, omnislam/runtime/pairing_options_table.h) drive the parser, SlamProcessOptions::validate()
// and the start-up echo: every numeric key accepts its range's end and refuses beyond it naming the
// key, the member beyond its range fails validate() naming the field, every key of every shipped
// config file lands in its member (read here with yaml-cpp alone), and the echo prints every key.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "omnislam/runtime/slam_config.h"
#include "omnislam/runtime/slam_options_table.h"
#include "omnislam/core/angles.h"
#include "omnislam/core/slam/options_table.h"
#include "omnislam/runtime/pairing_options_table.h"

using namespace omnislam;
using namespace omnislam::runtime;
using options::Kind;

namespace {

std::string errorOf(const std::string& text) {
  try {
    parseSlamOptions(config::Node::loadString(text, "slam.yaml"));
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

bool numeric(Kind k) { return k == Kind::kReal || k == Kind::kInt || k == Kind::kSeconds || k == Kind::kUint64; }

// "section: {key: value, companions...}" (the top level when section is empty); a companion is a
// "key: value" the section needs beside the key under test (a fixed start pose needs all of it).
std::string yamlOf(const std::string& section, const std::string& key, const std::string& value,
                   const std::vector<std::string>& companions) {
  std::string body = key + ": " + value;
  for (const auto& c : companions)
    if (c.rfind(key + ":", 0) != 0) body += ", " + c;
  return section.empty() ? "{" + body + "}\n" : section + ": {" + body + "}\n";
}

// A member beyond its range (none for a setter that wraps into the range, theta_deg).
template <class S>
void setBeyond(const options::Field<S>& f, S& s) {
  switch (f.kind) {
    case Kind::kReal: f.setRealMember(s, f.memberHi() * 2.0 + 1.0); break;
    case Kind::kInt: s.*f.integer = static_cast<int>(f.hi) * 2 + 1; break;
    case Kind::kSeconds: s.*f.micros = static_cast<int64_t>(f.memberHi()) * 2 + 1; break;
    case Kind::kUint64: s.*f.u64 = std::numeric_limits<std::uint64_t>::max(); break;
    default: break;
  }
}

// Every numeric key of `table` (section `section`, the part of SlamProcessOptions `part` returns).
template <class S>
void expectTableDrivesParserAndValidate(const std::string& section, const std::vector<options::Field<S>>& table,
                                        const std::function<S&(SlamProcessOptions&)>& part,
                                        const std::vector<std::string>& companions = {}) {
  SlamProcessOptions defaults;
  EXPECT_EQ(options::checkRanges(part(defaults), table), "") << section << ": a default out of its range";
  for (const auto& f : table) {
    if (!numeric(f.kind)) continue;
    const double edge = f.bounds == options::Bounds::kHighOpen ? f.lo : f.hi;
    const bool whole = f.kind == Kind::kInt || f.kind == Kind::kUint64;
    const std::string edge_text = whole ? options::integerText(edge) : options::numberText(edge);
    SlamProcessOptions o =
        parseSlamOptions(config::Node::loadString(yamlOf(section, f.key, edge_text, companions), "x"));
    S expected = part(defaults);  // the member the edge should give, through the row's own setter
    if (f.kind == Kind::kReal) f.setRealMember(expected, f.degrees ? deg2rad(edge) : edge);
    const double want = f.kind == Kind::kReal ? f.memberValue(expected) : f.value(expected);
    const double got = f.kind == Kind::kReal ? f.memberValue(part(o)) : f.value(part(o));
    if (f.kind == Kind::kReal) EXPECT_NEAR(got, want, 1e-12 * std::max(1.0, std::abs(want))) << section << "." << f.key;
    else EXPECT_NEAR(got, edge, 1e-9 * std::max(1.0, std::abs(edge))) << section << "." << f.key;

    const std::string beyond = options::numberText((f.hi + 1.0) * 2.0);
    const std::string err = errorOf(yamlOf(section, f.key, beyond, companions));
    EXPECT_NE(err.find(std::string(f.key) + "' must be"), std::string::npos) << section << "." << f.key << ": " << err;

    setBeyond(f, part(o));
    if (f.memberInRange(f.memberValue(part(o)))) continue;  // theta_deg wraps into its range
    EXPECT_NE(o.validate().find(std::string(f.field) + " must be in "), std::string::npos)
        << section << "." << f.key << ": '" << o.validate() << "'";
  }
}

SlamProcessOptions& whole(SlamProcessOptions& o) { return o; }

TEST(SlamConfigTables, TablesDriveParserAndValidate) {
  expectTableDrivesParserAndValidate<SlamProcessOptions>("", topLevelFields(), whole);
  expectTableDrivesParserAndValidate<SlamProcessOptions>("start_pose", startPoseFields(), whole,
                                                         {"source: fixed", "x_m: 0", "y_m: 0", "theta_deg: 0"});
  expectTableDrivesParserAndValidate<SlamProcessOptions>("features", featureFields(), whole);
  expectTableDrivesParserAndValidate<SlamProcessOptions>("output", outputFields(), whole);
  expectTableDrivesParserAndValidate<SlamProcessOptions>("checkpoint", checkpointFields(), whole);
  expectTableDrivesParserAndValidate<PairingOptions>("pairing", pairingFields(),
                                                     [](SlamProcessOptions& o) -> PairingOptions& { return o.pairing; },
                                                     {"odometry_buffer_s: 36000"});  // >= max_wait_s at its end
  expectTableDrivesParserAndValidate<RestartOptions>(
      "restart", restartFields(), [](SlamProcessOptions& o) -> RestartOptions& { return o.restart; });
  expectTableDrivesParserAndValidate<PlausibilityOptions>(
      "plausibility", plausibilityFields(),
      [](SlamProcessOptions& o) -> PlausibilityOptions& { return o.plausibility; });
}

// Every key of the process's own sections lands in its member, in the member's units (written out
// here by hand: radians, microseconds, wrapped heading, resolved paths).
TEST(SlamConfigTables, EveryProcessKeyLandsInItsMemberInItsUnits) {
  const SlamProcessOptions o = parseSlamOptions(config::Node::loadString(
      "seed: 42\n"
      "start_pose: {source: fixed, x_m: 1.5, y_m: -2.5, theta_deg: 270}\n"
      "features: {use_ceiling_lights: false, use_vertical_lines: true, min_sigma_deg: 0.5, max_per_frame: 100}\n"
      "output: {map_every_n_frames: 3, odometry_only_after_s: 4.5, odometry_only_period_s: 0.25}\n"
      "map: {save_path: out/m.yaml, load_path: /abs/p.yaml, localisation_only: true}\n"
      "checkpoint: {path: c.ckpt, interval_s: 7.5}\n"
      "pairing: {max_wait_s: 1.5, max_odometry_gap_s: 0.25, odometry_buffer_s: 20, max_pending_frames: 16, "
      "restart_jump_s: 6, restart_confirm_messages: 3, max_forward_jump_s: 7, max_odometry_speed_mps: 2.5, "
      "max_odometry_yaw_rate_degps: 180}\n"
      "restart: {reinit_from: start_pose, position_sigma_m: 1.5, heading_sigma_deg: 45}\n"
      "plausibility: {max_odometry_coordinate_m: 500, max_odometry_angle_rad: 40, max_camera_offset_m: 2.5, "
      "jump_confirm_messages: 7}\n",
      "dir/slam.yaml"));
  EXPECT_EQ(o.validate(), "");
  EXPECT_EQ(o.seed, 42u);
  EXPECT_EQ(o.start_source, SlamProcessOptions::StartSource::kFixed);
  EXPECT_EQ(o.start_pose_W.x_m, 1.5);
  EXPECT_EQ(o.start_pose_W.y_m, -2.5);
  EXPECT_NEAR(o.start_pose_W.theta_rad, -kPi / 2, 1e-12);  // 270 deg, wrapped
  EXPECT_FALSE(o.use_ceiling_lights);
  EXPECT_TRUE(o.use_vertical_lines);
  EXPECT_EQ(o.min_sigma_rad, deg2rad(0.5));
  EXPECT_EQ(o.max_features_per_frame, 100);
  EXPECT_EQ(o.map_every_n_frames, 3);
  EXPECT_EQ(o.odometry_only_after_us, 4'500'000);
  EXPECT_EQ(o.odometry_only_period_us, 250'000);
  EXPECT_EQ(o.save_map_path, "dir/out/m.yaml");  // relative to the config file
  EXPECT_EQ(o.load_map_path, "/abs/p.yaml");
  EXPECT_TRUE(o.localisation_only);
  EXPECT_EQ(o.checkpoint_path, "dir/c.ckpt");
  EXPECT_EQ(o.checkpoint_interval_us, 7'500'000);
  EXPECT_EQ(o.pairing.max_wait_us, 1'500'000);
  EXPECT_EQ(o.pairing.max_odometry_gap_us, 250'000);
  EXPECT_EQ(o.pairing.odometry_buffer_us, 20'000'000);
  EXPECT_EQ(o.pairing.max_pending_frames, 16);
  EXPECT_EQ(o.pairing.restart_jump_us, 6'000'000);
  EXPECT_EQ(o.pairing.restart_confirm_messages, 3);
  EXPECT_EQ(o.pairing.max_forward_jump_us, 7'000'000);
  EXPECT_EQ(o.pairing.max_odometry_speed_mps, 2.5);
  EXPECT_EQ(o.pairing.max_odometry_yaw_rate_radps, deg2rad(180.0));
  EXPECT_EQ(o.restart.reinit_from, RestartOptions::ReinitFrom::kStartPose);
  EXPECT_EQ(o.restart.position_sigma_m, 1.5);
  EXPECT_EQ(o.restart.heading_sigma_rad, deg2rad(45.0));
  EXPECT_EQ(o.plausibility.max_odometry_coordinate_m, 500.0);
  EXPECT_EQ(o.plausibility.max_odometry_angle_rad, 40.0);
  EXPECT_EQ(o.plausibility.max_camera_offset_m, 2.5);
  EXPECT_EQ(o.plausibility.jump_confirm_messages, 7);
}

// A start_pose section needs its source; with fixed every pose key, with odometry none is read.
TEST(SlamConfigTables, StartPoseNeedsItsSourceAndAFixedPoseAllThreeKeys) {
  EXPECT_NE(errorOf("start_pose: {x_m: 1}\n").find("key 'start_pose.source' is missing"), std::string::npos);
  EXPECT_NE(errorOf("start_pose: {source: fixed, x_m: 1, y_m: 2}\n").find("key 'start_pose.theta_deg' is missing"),
            std::string::npos);
  const SlamProcessOptions odo =
      parseSlamOptions(config::Node::loadString("start_pose: {source: odometry, x_m: 1, y_m: 2, theta_deg: 3}\n", "x"));
  EXPECT_EQ(odo.start_source, SlamProcessOptions::StartSource::kOdometry);
  EXPECT_EQ(odo.start_pose_W.x_m, 0.0);
  EXPECT_EQ(odo.start_pose_W.theta_rad, 0.0);
}

// Issue 56: `start_pose.source: unknown` reads no pose keys; `localisation.*` through its table (the
// core's), its checks across keys named; unknown without a map to load is refused naming the key.
TEST(SlamConfigTables, UnknownStartAndLocalisationKeys) {
  const SlamProcessOptions o =
      parseSlamOptions(config::Node::loadString("start_pose: {source: unknown, x_m: 1}\nlocalisation: {min_frames: 5, "
                                                "max_range_m: 25}\nmap: {load_path: m.yaml}\n",
                                                "x"));
  EXPECT_EQ(o.start_source, SlamProcessOptions::StartSource::kUnknown);
  EXPECT_EQ(o.start_pose_W.x_m, 0.0) << "not read with unknown";
  EXPECT_EQ(o.localisation.min_frames, 5);
  EXPECT_EQ(o.localisation.max_range_m, 25.0);
  EXPECT_EQ(o.validate(), "");
  EXPECT_NE(describe(o).find("localisation: "), std::string::npos) << "echoed";
  const std::string range = errorOf("localisation: {min_frames: 0}\n");
  EXPECT_NE(range.find("key 'localisation.min_frames'"), std::string::npos) << range;
  const std::string across = errorOf("localisation: {min_matched: 9, max_seed_bearings: 8}\n");
  EXPECT_NE(across.find("key 'localisation.min_matched'"), std::string::npos) << across;
  EXPECT_NE(errorOf("localisation: {min_frame: 3}\n").find("localisation.min_frame"), std::string::npos);
  // Unknown with no map: the file alone parses (--load-map may give one), validate() names the key.
  const SlamProcessOptions no_map = parseSlamOptions(config::Node::loadString("start_pose: {source: unknown}\n", "x"));
  EXPECT_NE(no_map.validate().find("start_pose.source unknown needs map.load_path"), std::string::npos)
      << no_map.validate();
}

// Durations: seconds in the file, whole microseconds in the struct, exact in the echo.
TEST(SlamConfigTables, DurationsAreMicrosecondsOfTheSecondsWritten) {
  const SlamProcessOptions o = parseSlamOptions(config::Node::loadString(
      "output: {odometry_only_after_s: 0.1234567, odometry_only_period_s: 2.5}\npairing: {max_odometry_gap_s: "
      "0.0000015}\ncheckpoint: {interval_s: 1e6}\n",
      "x"));
  EXPECT_EQ(o.odometry_only_after_us, 123'457);  // to the nearest microsecond
  EXPECT_EQ(o.odometry_only_period_us, 2'500'000);
  EXPECT_EQ(o.pairing.max_odometry_gap_us, 2);
  EXPECT_EQ(o.checkpoint_interval_us, 1'000'000'000'000);
  const std::string echo = describe(o);
  EXPECT_NE(echo.find("odometry_only_after_s=0.123457 "), std::string::npos) << echo;
  EXPECT_NE(echo.find("max_odometry_gap_s=0.000002 "), std::string::npos) << echo;
  EXPECT_NE(echo.find("interval_s=1000000"), std::string::npos) << echo;
}

// A typo is refused with the keys the section accepts, from its table.
TEST(SlamConfigTables, UnknownKeysListTheTablesKeys) {
  EXPECT_NE(errorOf("restart: {heading_sigma_rad: 0.5}\n")
                .find("key 'restart.heading_sigma_rad' is not a known key (known here: reinit_from, position_sigma_m, "
                      "heading_sigma_deg)"),
            std::string::npos)
      << errorOf("restart: {heading_sigma_rad: 0.5}\n");
  EXPECT_NE(errorOf("checkpoint: {interval: 5}\n").find("(known here: path, interval_s)"), std::string::npos);
  const std::string root = errorOf("sed: 1\n");
  for (const char* k : {"seed", "start_pose", "localisation", "features", "output", "map", "checkpoint", "pairing",
                        "restart", "plausibility", "filter"})
    EXPECT_NE(root.find(k), std::string::npos) << k << " in " << root;
}

// Options set after the file (the command-line flags) are checked by validate() with the same ranges.
TEST(SlamConfigTables, ValidateChecksWhatTheFlagsSet) {
  SlamProcessOptions o;
  EXPECT_EQ(o.validate(), "");
  o.checkpoint_interval_us = 999;  // --checkpoint-interval 0.000999
  EXPECT_EQ(o.validate(), "checkpoint: checkpoint_interval_us must be in [1000, 1e+12], got 999");
  o = SlamProcessOptions{};
  o.localisation_only = true;  // --localise without a map
  EXPECT_NE(o.validate().find("needs map.load_path"), std::string::npos) << o.validate();
  o = SlamProcessOptions{};
  o.pairing.max_pending_frames = 0;
  EXPECT_EQ(o.validate(), "pairing: max_pending_frames must be in [1, 10000], got 0");
}

// ---- Shipped files and the echo ------------------------------------------------------------------

std::vector<std::string> shippedFiles() {
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(std::string(OMNISLAM_SOURCE_DIR) + "/config/slam"))
    if (e.path().extension() == ".yaml") files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

// n[key], or a null node when n is not a map or has no such key (yaml-cpp's lookup of a missing key
// gives a node that throws when asked anything).
YAML::Node childOf(const YAML::Node& n, const std::string& key) {
  if (!n.IsMap()) return YAML::Node();
  const YAML::Node c = n[key];
  return c.IsDefined() ? c : YAML::Node();
}

// The keys of one section of a file (`sec`, read with yaml-cpp alone) against the parsed part;
// a key the file leaves out holds the default's value.
template <class S>
void expectFileKeys(const YAML::Node& sec, const std::string& name, const std::string& dir, const S& parsed,
                    const S& defaults, const std::vector<options::Field<S>>& table) {
  for (const auto& f : table) {
    const std::string key = name + f.key;
    const YAML::Node v = childOf(sec, f.key);
    if (v.IsNull()) {
      EXPECT_EQ(options::valueText(f, parsed), options::valueText(f, defaults)) << key << ": absent, the default";
      continue;
    }
    switch (f.kind) {
      case Kind::kBool: EXPECT_EQ(f.flagMember(parsed), v.as<bool>()) << key; break;
      case Kind::kEnum: EXPECT_EQ(options::valueText(f, parsed), v.Scalar()) << key; break;
      case Kind::kPath:
        EXPECT_EQ(parsed.*f.text, (std::filesystem::path(dir) / v.Scalar()).lexically_normal().string()) << key;
        break;
      case Kind::kVec3:
        for (int i = 0; i < 3; ++i) EXPECT_DOUBLE_EQ((parsed.*f.vec3)(i), v[i].as<double>()) << key << "[" << i << "]";
        break;
      default: {
        const double want = v.as<double>();
        EXPECT_NEAR(f.value(parsed), want, 1e-12 * std::max(1.0, std::abs(want))) << key;
      }
    }
  }
}

void expectFileReadThroughTheTables(const std::string& file) {
  SCOPED_TRACE(file);
  const SlamProcessOptions o = loadSlamOptions(file);
  const YAML::Node y = YAML::LoadFile(file);
  const std::string dir = std::filesystem::path(file).parent_path().string();
  const SlamProcessOptions d;
  expectFileKeys(y, "", dir, o, d, topLevelFields());
  for (const auto& [name, table] : {std::pair{"start_pose", &startPoseFields},
                                    {"features", &featureFields},
                                    {"output", &outputFields},
                                    {"map", &mapFields},
                                    {"checkpoint", &checkpointFields}})
    expectFileKeys(childOf(y, name), std::string(name) + ".", dir, o, d, table());
  expectFileKeys(childOf(y, "pairing"), "pairing.", dir, o.pairing, d.pairing, pairingFields());
  expectFileKeys(childOf(y, "restart"), "restart.", dir, o.restart, d.restart, restartFields());
  expectFileKeys(childOf(y, "localisation"), "localisation.", dir, o.localisation, d.localisation,
                 slam::options::globalLocalisationFields());
  expectFileKeys(childOf(y, "lost"), "lost.", dir, o.lost, d.lost, slam::options::lostFields());
  expectFileKeys(childOf(y, "plausibility"), "plausibility.", dir, o.plausibility, d.plausibility,
                 plausibilityFields());
  // The filter's keys given beside its preset override it; the others hold the preset's values.
  const YAML::Node f = childOf(y, "filter");
  slam::FastSlamOptions preset;
  if (!childOf(f, "preset").IsNull()) {
    const auto& names = slam::presetNames();
    const auto at = std::find(names.begin(), names.end(), f["preset"].Scalar());
    ASSERT_NE(at, names.end());
    preset = slam::presetOptions(static_cast<slam::Preset>(at - names.begin()));
  }
  namespace opt = slam::options;
  expectFileKeys(f, "filter.", dir, o.filter, preset, opt::fastSlamFields());
  expectFileKeys(childOf(f, "motion"), "filter.motion.", dir, o.filter.motion, preset.motion, opt::motionFields());
  expectFileKeys(childOf(f, "perception"), "filter.perception.", dir, o.filter.perception, preset.perception,
                 opt::perceptionFields());
  expectFileKeys(childOf(f, "candidates"), "filter.candidates.", dir, o.filter.candidates, preset.candidates,
                 opt::candidateFields());
}

TEST(SlamConfigTables, EveryShippedFileIsReadKeyByKeyIntoItsMembers) {
  const auto files = shippedFiles();
  ASSERT_GE(files.size(), 3u);
  for (const auto& file : files) expectFileReadThroughTheTables(file);
}

// The echo's part of a section, "name: k=v ..." from the start of a line or after "; " (the files
// of one run share the last line) to the end of the line or the next "; "; the top level's starts
// a line with its first key.
std::string echoLine(const std::string& echo, const std::string& name) {
  std::istringstream in(echo);
  const std::string head = name.empty() ? topLevelFields().front().key + std::string("=") : name + ": ";
  for (std::string line; std::getline(in, line);) {
    std::size_t at = line.rfind(head, 0) == 0 ? 0 : line.find("; " + head);
    if (at == std::string::npos) continue;
    if (at > 0) at += 2;
    const std::size_t begin = at + (name.empty() ? 0 : head.size()), end = line.find("; ", begin);
    return " " + line.substr(begin, end == std::string::npos ? std::string::npos : end - begin) + " ";
  }
  return "";
}

template <class S>
void expectEchoed(const std::string& echo, const std::string& name, const S& part,
                  const std::vector<options::Field<S>>& table) {
  const std::string line = echoLine(echo, name);
  ASSERT_FALSE(line.empty()) << "no line '" << name << ": ' in\n" << echo;
  for (const auto& f : table) {
    const std::string kv = " " + std::string(f.key) + "=" + options::valueText(f, part) + " ";
    EXPECT_NE(line.find(kv), std::string::npos) << kv << " not in the line of " << name << ":" << line;
  }
}

// The start-up echo prints every key of every section with its value (a checkpoint's fingerprint
// compares it, but for the last line: the files of one run, `map: ...; checkpoint: ...`).
TEST(SlamConfigTables, TheEchoPrintsEveryKeyOfEverySection) {
  for (const auto& file : shippedFiles()) {
    SCOPED_TRACE(file);
    SlamProcessOptions o = loadSlamOptions(file);
    o.save_map_path = "/tmp/m.yaml", o.checkpoint_path = "/tmp/c.ckpt";
    const std::string echo = describe(o);
    expectEchoed(echo, "", o, topLevelFields());
    expectEchoed(echo, "start_pose", o, startPoseFields());
    expectEchoed(echo, "features", o, featureFields());
    expectEchoed(echo, "output", o, outputFields());
    expectEchoed(echo, "map", o, mapFields());
    expectEchoed(echo, "checkpoint", o, checkpointFields());
    expectEchoed(echo, "pairing", o.pairing, pairingFields());
    expectEchoed(echo, "restart", o.restart, restartFields());
    expectEchoed(echo, "plausibility", o.plausibility, plausibilityFields());
    expectEchoed(echo, "localisation", o.localisation, slam::options::globalLocalisationFields());
    expectEchoed(echo, "lost", o.lost, slam::options::lostFields());
    namespace opt = slam::options;
    expectEchoed(echo, "filter", o.filter, opt::fastSlamFields());
    expectEchoed(echo, "filter.motion", o.filter.motion, opt::motionFields());
    expectEchoed(echo, "filter.perception", o.filter.perception, opt::perceptionFields());
    expectEchoed(echo, "filter.candidates", o.filter.candidates, opt::candidateFields());
    EXPECT_NE(echo.find("\ndeviations from paper 000: "), std::string::npos) << echo;
    // The files of one run last, on the one line a checkpoint's fingerprint leaves out.
    EXPECT_EQ(echo.substr(echo.rfind('\n') + 1).rfind("map: save_path=/tmp/m.yaml ", 0), 0u) << echo;
    EXPECT_NE(echo.substr(echo.rfind('\n') + 1).find("; checkpoint: path=/tmp/c.ckpt "), std::string::npos) << echo;
  }
}

}  // namespace
