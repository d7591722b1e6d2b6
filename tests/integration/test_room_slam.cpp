// Paper 002's pipeline end to end on the simulated room, live: simulator, catadioptric colour
// capture, translate-then-rotate odometry, vertical-line features and the SLAM process with the
// paper's method (FastSLAM 1.0 + per-measurement ML, config/slam/room.yaml) on a private LCM URL,
// recorded, then scored in 2D with omnislam-eval against the truth. The bar is paper 002's floor
// tile: path RMSE and mean landmark error below 0.30 m; every frame is answered. The recording is
// then replayed offline, as scripts/reproduce-room.sh does, and must meet the same bar.
#include <gtest/gtest.h>

#include "eval_json.h"
#include "proc_util.h"
#include "slam_log.h"

using namespace omnislam;
namespace t = omnislam::testing;
using omnislam::testing::jsonNumber;

namespace {

void expectWithinTheTile(const std::string& eval_json) {
  EXPECT_LT(jsonNumber(eval_json, "ate_rmse_m"), 0.30) << eval_json;
  EXPECT_LT(jsonNumber(eval_json, "landmark_mean_err_m"), 0.30) << eval_json;
  EXPECT_GE(jsonNumber(eval_json, "landmarks_matched"), 19) << "half of the 38 lines mapped: " << eval_json;
  EXPECT_LE(jsonNumber(eval_json, "landmarks_spurious"), 1) << eval_json;
}

TEST(RoomSlam, LiveAndReplayWithinOneFloorTile) {
  // Seed 6 of docs/results/room-scenario.md (seeds 1-10 all pass there; seed 6 is the third best of the ten,
  // path 0.086 m: the test guards the pipeline, the tables measure the method).
  // 10 s of wall time at speedup 4 before a stalled process counts as dead (the launch file's 3 s,
  // as in the full-system test: the test checks the method, not how fast a loaded machine runs it).
  t::LaunchedRun run("config/launch/room_slam.yaml", 17,
                     {"speedup=4", "odometry_only_after_s=40", "seed=6", "slam_seed=6"}, 240.0);
  ASSERT_EQ(run.result.exit_code, 0) << run.result.output;
  EXPECT_EQ(run.result.output.find("died"), std::string::npos) << run.result.output;
  const size_t num_frames = t::expectEveryFrameAnswered(run.log);
  if (HasFailure()) std::cout << "the run's output:\n" << run.result.output;
  ASSERT_GE(num_frames, 200u) << "2 Hz over the 101 s trajectory";
  const auto ev = t::run({t::binPath("omnislam-eval"), run.log, "--planar", "--json", "--no-tum"}, 60);
  ASSERT_EQ(ev.exit_code, 0) << ev.output;
  std::cout << "live: " << ev.output;
  expectWithinTheTile(ev.output);

  const std::string out = run.dir.file("replay.lcm");
  const auto r = t::run({t::binPath("omnislam-slam"), "--config", t::sourcePath("config/slam/room.yaml"), "--seed", "6",
                         "--replay", run.log, "--out", out, "--no-progress"},
                        180);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto ev2 = t::run({t::binPath("omnislam-eval"), out, "--planar", "--json", "--no-tum"}, 60);
  ASSERT_EQ(ev2.exit_code, 0) << ev2.output;
  std::cout << "replay: " << ev2.output;
  expectWithinTheTile(ev2.output);
}

}  // namespace
