// scripts/mrclam_seed_table.py (the table of scripts/run-mrclam.sh --seeds): medians, ranges and the
// count of runs meeting issue 7's three bars, on evaluation files the test writes with known values,
// including the bars' edges, a run without a matched landmark, and unreadable input.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "proc_util.h"

namespace {

using omnislam::testing::run;
using omnislam::testing::sourcePath;
using omnislam::testing::TempDir;

void writeEval(const TempDir& dir, int robot, int seed, double ate_m, double landmark_mean_m, int matched,
               int spurious) {
  std::ofstream f(dir.file("robot" + std::to_string(robot) + ".seed" + std::to_string(seed) + ".eval-aligned.json"));
  f << "{\"ate_rmse_m\": " << ate_m << ", \"landmark_mean_err_m\": " << landmark_mean_m
    << ", \"landmarks_matched\": " << matched << ", \"landmarks_spurious\": " << spurious
    << ", \"dr_ate_rmse_aligned_m\": 2.5}\n";
}

omnislam::testing::RunResult table(const TempDir& dir, const std::string& robots, const std::string& seeds) {
  return run({"python3", sourcePath("scripts/mrclam_seed_table.py"), dir.path(), "--robots", robots, "--seeds", seeds},
             30.0);
}

TEST(MrclamSeedTable, MediansRangesAndRunsMeetingTheBars) {
  TempDir dir;
  // Robot 1: every run exactly at a bar meets it (<= 0.4 m, <= 0.35 m, <= 5 spurious).
  writeEval(dir, 1, 1, 0.40, 0.35, 4, 5);
  writeEval(dir, 1, 2, 0.30, 0.20, 6, 0);
  writeEval(dir, 1, 3, 0.90, 0.10, 6, 1);  // ATE over the bar
  // Robot 2: just over each bar in turn, and one run with no matched landmark (mean undefined).
  writeEval(dir, 2, 1, 0.41, 0.10, 6, 0);
  writeEval(dir, 2, 2, 0.10, 0.36, 6, 0);
  writeEval(dir, 2, 3, 0.10, 0.0, 0, 6);
  const auto r = table(dir, "1 2", "1 2 3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("| 1 | 3 | 0.40 [0.30, 0.90] | 0.20 [0.10, 0.35] | 1 [0, 5] | 2.50 [2.50, 2.50] | 2 |"),
            std::string::npos)
      << r.output;
  // The landmark mean of robot 2 is over the two runs with a matched landmark only.
  EXPECT_NE(r.output.find("| 2 | 3 | 0.10 [0.10, 0.41] | 0.23 [0.10, 0.36] | 0 [0, 6] | 2.50 [2.50, 2.50] | 0 |"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("| all | 6 | 0.35 [0.10, 0.90] | 0.20 [0.10, 0.36] | 0.5 [0, 6] | 2.50 [2.50, 2.50] | 2 |"),
            std::string::npos)
      << r.output;
}

TEST(MrclamSeedTable, NamesTheMissingOrMalformedFile) {
  TempDir dir;
  writeEval(dir, 1, 1, 0.5, 0.5, 3, 2);
  auto r = table(dir, "1", "1 2");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("robot1.seed2.eval-aligned.json"), std::string::npos) << r.output;

  std::ofstream(dir.file("robot1.seed2.eval-aligned.json")) << "{\"ate_rmse_m\": 0.3,";
  r = table(dir, "1", "1 2");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("robot1.seed2.eval-aligned.json: not JSON"), std::string::npos) << r.output;

  std::ofstream(dir.file("robot1.seed2.eval-aligned.json")) << "{\"frames\": 3}";
  r = table(dir, "1", "1 2");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("no 'ate_rmse_m'"), std::string::npos) << r.output;

  r = table(dir, "1", "one");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--seeds takes integers"), std::string::npos) << r.output;
}

}  // namespace
