// scripts/run-mrclam.sh, the documented MRCLAM command: every bad flag stops it at once with the flag
// named (exit 2), it runs importer, filter and evaluation end to end on a small MRCLAM-format dataset
// the test writes (one seed and several), and a failing step stops it with the step and its message.
// Also the --help of the scripts that share scripts/lib/options.sh: their header comment, all of it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "mrclam_files.h"
#include "proc_util.h"

namespace {

namespace t = omnislam::testing;

/// Robot 1 for 60 s: 0.1 m/s, turning at 0.05 rad/s, odometry and truth at 10 Hz (the truth is the
/// odometry integrated exactly), four landmarks, and a frame every 0.5 s with the exact bearing of each
/// landmark within +-0.6 rad and 0.9-8 m, plus a sighting of robot 2 (clutter) in every fourth frame.
/// Returns the number of frames (times with at least one sighting).
int writeDataset(const t::TempDir& d) {
  t::writeMrclamFile(d.file("Barcodes.dat"), "1 5\n2 14\n6 63\n7 81\n8 27\n9 54\n");
  const double lm[4][2] = {{4.0, 1.5}, {4.5, -1.0}, {3.0, 3.5}, {1.0, 4.0}};
  const int code[4] = {63, 81, 27, 54};
  std::string lms;
  for (int j = 0; j < 4; ++j) {
    lms += std::to_string(6 + j) + " " + std::to_string(lm[j][0]) + " " + std::to_string(lm[j][1]) + " 0.001 0.001\n";
  }
  t::writeMrclamFile(d.file("Landmark_Groundtruth.dat"), lms);
  std::string odo, truth, meas;
  double x = 0.0, y = 0.0, th = 0.0;
  const double v = 0.1, w = 0.05, dt = 0.1;
  char line[160];
  int frames = 0;
  for (int k = 0; k <= 600; ++k) {
    const double time = 1000.0 + dt * k;
    std::snprintf(line, sizeof line, "%.3f %.3f %.3f\n", time, v, w);
    odo += line;
    std::snprintf(line, sizeof line, "%.3f %.6f %.6f %.6f\n", time, x, y, th);
    truth += line;
    if (k > 0 && k % 5 == 0) {
      bool seen = k % 20 == 0;
      for (int j = 0; j < 4; ++j) {
        const double dx = lm[j][0] - x, dy = lm[j][1] - y;
        const double r = std::hypot(dx, dy);
        const double b = std::remainder(std::atan2(dy, dx) - th, 2.0 * M_PI);
        if (std::abs(b) > 0.6 || r < 0.9 || r > 8.0) continue;
        seen = true;
        std::snprintf(line, sizeof line, "%.3f %d %.4f %.6f\n", time, code[j], r, b);
        meas += line;
      }
      if (k % 20 == 0) {
        std::snprintf(line, sizeof line, "%.3f 14 2.0 %.6f\n", time, 0.3 * std::sin(0.1 * k));
        meas += line;
      }
      frames += seen ? 1 : 0;
    }
    x += v * dt * std::cos(th + 0.5 * w * dt);
    y += v * dt * std::sin(th + 0.5 * w * dt);
    th += w * dt;
  }
  t::writeMrclamFile(d.file("Robot1_Odometry.dat"), odo);
  t::writeMrclamFile(d.file("Robot1_Groundtruth.dat"), truth);
  t::writeMrclamFile(d.file("Robot1_Measurement.dat"), meas);
  return frames;
}

std::string buildDir() { return std::filesystem::path(t::binPath("")).parent_path().parent_path().string(); }

t::RunResult script(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {"bash", t::sourcePath("scripts/run-mrclam.sh")};
  argv.insert(argv.end(), args.begin(), args.end());
  return t::run(argv, 120.0);
}

TEST(MrclamRunScript, BadFlagsStopAtOnceNamingTheFlag) {
  t::TempDir out;
  const std::string o = out.path();
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const Case cases[] = {
      {{"--out", o, "--seeds"}, "--seeds needs a value"},
      {{"--out", o, "--robots"}, "--robots needs a value"},
      {{"--out", o, "--seed", "x"}, "--seed takes one non-negative integer (several: --seeds), got 'x'"},
      // Two seeds into one run's files: the second overwrote the first's robotN.* files.
      {{"--out", o, "--seed", "1 2"}, "--seed takes one non-negative integer (several: --seeds), got '1 2'"},
      {{"--out", o, "--seeds", "1 -2"}, "--seeds takes non-negative integers, got '-2'"},
      {{"--out", o, "--seed", "1", "--seeds", "1 2"}, "give --seed or --seeds, not both"},
      {{"--out", o, "--robots", "1,2"}, "--robots takes robot numbers (1-5 in dataset 6), got '1,2'"},
      {{"--out", o, "--robots", " "}, "--robots needs at least one robot number"},
      {{"--out", o, "--config", o + "/missing.yaml"}, "--config: no such file"},
      {{"--out", o, "--particles", "3"}, "unknown argument '--particles'"},
  };
  for (const auto& c : cases) {
    const auto r = script(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.message << "\n" << r.output;
    EXPECT_NE(r.output.find("run-mrclam.sh: " + c.message), std::string::npos) << r.output;
  }
  // Nothing was run: no output file was written.
  EXPECT_TRUE(std::filesystem::is_empty(o));
}

TEST(MrclamRunScript, HelpIsTheWholeHeaderCommentOfEachScript) {
  struct Case {
    std::string script, first_line, usage;
  };
  const Case cases[] = {
      {"scripts/run-mrclam.sh", "Bearing-only SLAM on the five robots", "scripts/run-mrclam.sh [--build DIR]"},
      {"scripts/reproduce-room.sh", "Paper 002 end to end", "scripts/reproduce-room.sh [--seeds"},
      {"scripts/reproduce-table1.sh", "Reproduces paper 000's table I", "Takes about 45 s per seed"},
  };
  for (const auto& c : cases) {
    const auto r = t::run({"bash", t::sourcePath(c.script), "--help"}, 30.0);
    EXPECT_EQ(r.exit_code, 0) << c.script << "\n" << r.output;
    EXPECT_EQ(r.output.rfind(c.first_line, 0), 0u) << c.script << "\n" << r.output;
    EXPECT_NE(r.output.find(c.usage), std::string::npos) << c.script << "\n" << r.output;
    // Comment markers stripped, and no code after the header.
    EXPECT_EQ(r.output.find("\n#"), std::string::npos) << c.script << "\n" << r.output;
    EXPECT_EQ(r.output.find("set -euo pipefail"), std::string::npos) << c.script << "\n" << r.output;
  }
}

TEST(MrclamRunScript, RunsEndToEndOnASmallDatasetAndNamesAFailingStep) {
  t::TempDir data, out;
  const int frames = writeDataset(data);
  ASSERT_GT(frames, 60);
  const std::vector<std::string> common = {"--build", buildDir(), "--data", data.path(), "--robots", "1"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> a = common;
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  };

  // One seed: the per-run table with robot 1's row; exact odometry, so dead reckoning is near zero.
  auto r = script(with({"--out", out.file("one")}));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("MRCLAM " + std::filesystem::path(data.path()).filename().string() +
                          ", config mrclam.yaml, seed 1"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("| 1 | " + std::to_string(frames) + " | 0.00 / 0.00 | "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("/4 | "), std::string::npos) << r.output;  // matched out of the dataset's 4 landmarks
  for (const char* f :
       {"robot1.lcm", "robot1.yaml", "robot1.slam.lcm", "robot1.eval.json", "robot1.eval-aligned.json"}) {
    EXPECT_TRUE(std::filesystem::exists(out.file(std::string("one/") + f))) << f;
  }

  // Two seeds: the spread table, each run's files under robot1.seedS.
  r = script(with({"--out", out.file("two"), "--seeds", "3 4"}));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("seeds 3 4"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("| 1 | 2 | "), std::string::npos) << r.output;
  EXPECT_TRUE(std::filesystem::exists(out.file("two/robot1.seed4.eval-aligned.json")));

  // A step that fails stops the script with the step's name and the end of its messages.
  r = script(with({"--out", out.file("bad"), "--slam-args", "--set filter.particles=0"}));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("run-mrclam.sh: omnislam-slam, robot 1, seed 1 failed (exit 2)"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("filter.particles"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("| robot |"), std::string::npos) << r.output;

  // A robot without files: the importer's message names the file.
  r = script(with({"--out", out.file("missing"), "--robots", "2"}));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("omnislam-import-mrclam, robot 2 failed"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Robot2_Odometry.dat"), std::string::npos) << r.output;
}

}  // namespace
