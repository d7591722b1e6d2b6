// omnislam-gen-world and scripts/evaluate-worlds.sh (docs/results/world-families.md): the tool writes the
// same world file and log for the same seed; the log holds the messages the live system records,
// every one decoding and validating, in utime order; omnislam-slam replays it and answers every
// frame; the script runs a family of 2 worlds end to end (both association methods) and writes its
// table and summary; bad flags stop it at once.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>

#include "omnislam/feature_labels_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/decode.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/validate.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "proc_util.h"

namespace {

namespace t = omnislam::testing;
using namespace omnislam;

std::string buildDir() { return std::filesystem::path(t::binPath("")).parent_path().parent_path().string(); }

t::RunResult genWorld(const t::TempDir& d, const std::string& tag, const std::string& family, const std::string& seed) {
  return t::run({t::binPath("omnislam-gen-world"), "--family", family, "--seed", seed, "--out-world",
                 d.file(tag + ".yaml"), "--out-log", d.file(tag + ".lcm"), "--out-info", d.file(tag + ".json")},
                60.0);
}

template <class Msg>
bool decodesAndValidates(const lcmio::LogEvent& ev, int64_t* utime) {
  const auto m = lcmio::decodeAs<Msg>(ev);
  if (!m || lcmio::validate(*m)) return false;
  *utime = m->utime;
  return true;
}

TEST(GenWorld, SameSeedSameBytesAndTheLogDecodesInUtimeOrder) {
  t::TempDir d;
  ASSERT_EQ(genWorld(d, "a", "irregular", "3").exit_code, 0);
  ASSERT_EQ(genWorld(d, "b", "irregular", "3").exit_code, 0);
  EXPECT_EQ(t::readFile(d.file("a.yaml")), t::readFile(d.file("b.yaml")));
  EXPECT_EQ(t::readFile(d.file("a.lcm")), t::readFile(d.file("b.lcm")));
  EXPECT_EQ(t::readFile(d.file("a.json")), t::readFile(d.file("b.json")));

  std::map<std::string, int> count;
  int64_t last = 0;
  int bad = 0, out_of_order = 0;
  lcmio::forEachEvent(d.file("a.lcm"), [&](const lcmio::LogEvent& ev) {
    int64_t utime = 0;
    bool ok = false;
    if (ev.channel == channels::kGroundTruthPose) ok = decodesAndValidates<pose_t>(ev, &utime);
    if (ev.channel == channels::kOdometry) ok = decodesAndValidates<odometry_t>(ev, &utime);
    if (ev.channel == channels::kOmniFeatures) ok = decodesAndValidates<features_t>(ev, &utime);
    if (ev.channel == channels::kGroundTruthMap) ok = decodesAndValidates<map_t>(ev, &utime);
    if (ev.channel == channels::kGroundTruthFeatureLabels) ok = decodesAndValidates<feature_labels_t>(ev, &utime);
    bad += ok ? 0 : 1;
    out_of_order += utime < last ? 1 : 0;
    last = utime;
    ++count[ev.channel];
  });
  EXPECT_EQ(bad, 0);
  EXPECT_EQ(out_of_order, 0);
  EXPECT_EQ(count[channels::kGroundTruthPose], count[channels::kOdometry]);
  EXPECT_EQ(count[channels::kOmniFeatures], count[channels::kGroundTruthFeatureLabels]);
  const std::string info = t::readFile(d.file("a.json"));
  EXPECT_NE(info.find("\"frames\": " + std::to_string(count[channels::kOmniFeatures]) + ","), std::string::npos)
      << info;
  EXPECT_GT(count[channels::kOmniFeatures], 100);
  EXPECT_GT(count[channels::kGroundTruthMap], 0);

  // Replayed through the SLAM: every frame processed.
  const auto r = t::run({t::binPath("omnislam-slam"), "--replay", d.file("a.lcm"), "--config",
                         t::sourcePath("config/slam/sports_hall.yaml"), "--out", d.file("out.lcm"), "--no-progress"},
                        120.0);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string n = std::to_string(count[channels::kOmniFeatures]);
  EXPECT_NE(r.output.find("frames " + n + " processed " + n + " "), std::string::npos) << r.output;
}

TEST(GenWorld, BadFlagsStopWithExitCode2) {
  t::TempDir d;
  auto r = t::run({t::binPath("omnislam-gen-world"), "--family", "hall", "--out-world", d.file("w.yaml")}, 30.0);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--family must be halls, irregular or corridors"), std::string::npos) << r.output;
  r = t::run({t::binPath("omnislam-gen-world"), "--family", "halls", "--world", "x.yaml"}, 30.0);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = t::run({t::binPath("omnislam-gen-world"), "--family", "halls", "--rate-hz", "0"}, 30.0);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  // --rate-hz and --out-world belong to a drawn world; nothing to write is a mistake too.
  r = t::run({t::binPath("omnislam-gen-world"), "--world", t::sourcePath("config/worlds/sports_hall.yaml"), "--rate-hz",
              "5", "--out-log", d.file("l.lcm")},
             30.0);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = t::run({t::binPath("omnislam-gen-world"), "--family", "halls"}, 30.0);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("at least one of --out-world, --out-log, --out-info"), std::string::npos) << r.output;
  // A room world has no lights for this simulation: refused, not an empty log.
  r = t::run({t::binPath("omnislam-gen-world"), "--world", t::sourcePath("config/worlds/room.yaml"), "--out-log",
              d.file("l.lcm")},
             30.0);
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("needs a world of ceiling lights"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(d.file("w.yaml")));
  EXPECT_FALSE(std::filesystem::exists(d.file("l.lcm")));
}

TEST(EvaluateWorldsScript, TwoCorridorsEndToEndWithBothMethods) {
  t::TempDir d;
  const auto r = t::run({"bash", t::sourcePath("scripts/evaluate-worlds.sh"), "--family", "corridors", "--worlds", "2",
                         "--first-seed", "5", "--jobs", "2", "--out", d.file("out")},
                        240.0, {"OMNISLAM_BUILD_DIR=" + buildDir()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("| figure | Hungarian | ML |"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("| **pass rate** | **"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("world 5 done"), std::string::npos) << r.output;  // progress
  EXPECT_NE(r.output.find("world 6 done"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("failed"), std::string::npos) << r.output;
  for (const char* f : {"summary.json", "table.md", "eval-hungarian-5.json", "eval-ml-6.json", "world-6.yaml"})
    EXPECT_TRUE(std::filesystem::exists(d.file(std::string("out/") + f))) << f;
  const std::string summary = t::readFile(d.file("out/summary.json"));
  EXPECT_NE(summary.find("\"worlds\": 2"), std::string::npos) << summary;
}

TEST(EvaluateWorldsScript, BadFlagsStopAtOnce) {
  t::TempDir d;
  const std::string sh = t::sourcePath("scripts/evaluate-worlds.sh");
  const std::pair<std::vector<std::string>, std::string> cases[] = {
      {{"--family", "hall"}, "--family must be halls, irregular or corridors"},
      {{"--family", "halls", "--association", "sampled"}, "--association must be hungarian, ml or both"},
      {{"--family", "halls", "--worlds", "x"}, "--worlds takes non-negative integers"},
      {{"--family", "halls", "--jobs", "0"}, "--worlds, --jobs and --first-seed must be >= 1"},
      {{"--family", "halls", "--rate-hz", "fast"}, "--rate-hz takes a positive number"},
      {{"--family", "halls", "--worlds"}, "--worlds needs a value"},
  };
  for (const auto& [args, message] : cases) {
    std::vector<std::string> argv = {"bash", sh, "--out", d.file("o")};
    argv.insert(argv.end(), args.begin(), args.end());
    const auto r = t::run(argv, 30.0);
    EXPECT_EQ(r.exit_code, 2) << message << "\n" << r.output;
    EXPECT_NE(r.output.find("evaluate-worlds: " + message), std::string::npos) << r.output;
  }
  EXPECT_FALSE(std::filesystem::exists(d.file("o")));
  // --help: the header comment, markers stripped.
  const auto h = t::run({"bash", sh, "--help"}, 30.0);
  EXPECT_EQ(h.exit_code, 0) << h.output;
  EXPECT_EQ(h.output.rfind("Evaluates the SLAM on a family of generated worlds", 0), 0u) << h.output;
  EXPECT_NE(h.output.find("[--association hungarian|ml|both] [--jobs 2]"), std::string::npos) << h.output;
}

}  // namespace
