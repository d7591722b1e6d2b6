// MRCLAM dataset 6 end to end on a short stretch (docs/results/mrclam.md): omnislam-import-mrclam (robot
// sightings kept as clutter, the start pose written into a copy of config/slam/mrclam.yaml),
// omnislam-slam --replay, omnislam-eval --align --json; every frame answered, the figures present
// and the error bounded. Skips with a message when the dataset is absent.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <regex>

#include "datasets.h"
#include "eval_json.h"
#include "proc_util.h"

namespace t = omnislam::testing;
using omnislam::testing::jsonNumber;

namespace {

TEST(MrclamEndToEnd, ShortStretchOfRobot3) {
  const std::string dir = t::datasetPath("mrclam/MRCLAM_Dataset6");
  if (!std::filesystem::exists(dir + "/Robot3_Odometry.dat"))
    GTEST_SKIP() << "MRCLAM dataset 6 not found at " << dir << " (set OMNISLAM_DATASETS)";
  t::TempDir d;
  const std::string log = d.file("r3.lcm"), cfg = d.file("r3.yaml"), out = d.file("r3.slam.lcm");
  constexpr double kStretchS = 240.0;
  auto r = t::run({t::binPath("omnislam-import-mrclam"), dir, "--robot", "3", "--out", log, "--duplicate-times",
                   "keep-last", "--max-duration-s", std::to_string(kStretchS), "--slam-config-template",
                   t::sourcePath("config/slam/mrclam.yaml"), "--slam-config-out", cfg},
                  60);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("of other robots (kept as clutter)"), std::string::npos) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("OMNI_FEATURES: ([0-9]+) frames"))) << r.output;
  const int frames = std::stoi(m[1]);
  EXPECT_GT(frames, 300);

  r = t::run({t::binPath("omnislam-slam"), "--replay", log, "--out", out, "--config", cfg, "--seed", "1"}, 120);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("processed " + std::to_string(frames) + " dropped: no_odometry 0 odometry_gap 0 too_old 0"),
            std::string::npos)
      << r.output;

  r = t::run({t::binPath("omnislam-eval"), out, "--planar", "--json", "--no-tum", "--align"}, 60);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string& j = r.output;
  EXPECT_NE(j.find("\"assoc_available\": true"), std::string::npos) << j;
  EXPECT_NE(j.find("\"dr_available\": true"), std::string::npos) << j;
  const double slam_ate = jsonNumber(j, "ate_rmse_m"), dr_ate = jsonNumber(j, "dr_ate_rmse_aligned_m");
  std::cout << "robot 3, first " << kStretchS << " s: SLAM ATE aligned " << slam_ate << " m, dead reckoning aligned "
            << dr_ate << " m, landmarks matched " << jsonNumber(j, "landmarks_matched") << ", spurious "
            << jsonNumber(j, "landmarks_spurious") << ", association precision " << jsonNumber(j, "assoc_precision")
            << " recall " << jsonNumber(j, "assoc_recall") << std::endl;
  // Bounds. Measured 2026-11-22 (docs/results/mrclam.md): SLAM 0.87 m aligned (FastSLAM 2.0 before: 1.15 m),
  // dead reckoning 0.50 m, 4 landmarks matched, 2 spurious. The ATE bound is a guard against divergence and regressions
  // at today's level, NOT issue 7's bar (0.4 m over whole runs), which the filter does not meet yet; the spurious bound
  // is the (at most 5).
  EXPECT_LT(slam_ate, 1.5);
  EXPECT_LE(jsonNumber(j, "landmarks_spurious"), 5);
}

}  // namespace
