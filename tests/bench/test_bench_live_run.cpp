// The bench programs' helpers that are not timing (bench/live_run.h, bench/world_variant.h): the
// /proc parsers on written lines, the CPU and slope arithmetic, and the world made for a live run
// (another image rate; the path driven back and forth).
#include <gtest/gtest.h>

#include <cmath>
#include <unistd.h>

#include "live_run.h"
#include "omnislam/config/world_config.h"
#include "world_variant.h"

using namespace omnislam;

TEST(BenchProcStat, ReadsTheFieldsAfterANameWithSpacesAndParentheses) {
  const std::string line =
      "4242 (omni (x) y) S 4100 4242 4100 0 -1 4194560 1234 0 0 0 1503 207 0 0 20 0 3 0 900 100000 2000";
  const auto s = bench::parseProcStat(line);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->pid, 4242);
  EXPECT_EQ(s->comm, "omni (x) y");
  EXPECT_EQ(s->ppid, 4100);
  EXPECT_EQ(s->utime_ticks, 1503);
  EXPECT_EQ(s->stime_ticks, 207);
}

TEST(BenchProcStat, RefusesTruncatedLines) {
  EXPECT_FALSE(bench::parseProcStat(""));
  EXPECT_FALSE(bench::parseProcStat("12 (name S 1 2 3"));
  EXPECT_FALSE(bench::parseProcStat("12 (name) S 1 2 3 4 5 6 7 8 9"));  // stops before utime
}

TEST(BenchProcStat, ReadsThisProcess) {
  const auto s = bench::readProcStat(std::to_string(getpid()));
  ASSERT_TRUE(s);
  EXPECT_EQ(s->pid, getpid());
  EXPECT_EQ(s->ppid, getppid());
  const bench::ProcMem m = bench::parseProcStatus(bench::readWhole("/proc/self/status"));
  EXPECT_GT(m.rss_kb, 0);
  EXPECT_GE(m.hwm_kb, m.rss_kb);
}

TEST(BenchProcStatus, ReadsRssAndPeakAndSaysWhatIsAbsent) {
  const auto m = bench::parseProcStatus("Name:\tx\nVmHWM:\t   20480 kB\nVmRSS:\t   10240 kB\nThreads:\t1\n");
  EXPECT_EQ(m.rss_kb, 10240);
  EXPECT_EQ(m.hwm_kb, 20480);
  const auto zombie = bench::parseProcStatus("Name:\tx\nState:\tZ (zombie)\n");
  EXPECT_EQ(zombie.rss_kb, -1);
  EXPECT_EQ(zombie.hwm_kb, -1);
}

TEST(BenchProgramName, IsTheLastComponentOfArgvZero) {
  EXPECT_EQ(bench::programName(std::string("/a/b/omnislam-slam\0--config\0x.yaml\0", 35)), "omnislam-slam");
  EXPECT_EQ(bench::programName(std::string("omnislam-sim\0", 13)), "omnislam-sim");
  EXPECT_EQ(bench::programName(""), "");
}

TEST(BenchCpu, UsesTheSamplesInsideTheWindowAndSumsAProgramsProcesses) {
  bench::ProcSeries a{
      "omnislam-features", 10, {{0.0, 1.0, 0, 0}, {1.0, 1.5, 0, 0}, {3.0, 2.5, 0, 0}, {4.0, 9.0, 0, 0}}};
  const bench::CpuUse u = bench::cpuBetween(a, 0.5, 3.5);
  EXPECT_DOUBLE_EQ(u.cpu_s, 1.0);  // samples at 1 s and 3 s
  EXPECT_DOUBLE_EQ(u.wall_s, 2.0);
  EXPECT_DOUBLE_EQ(u.fractionOfOneCore(), 0.5);
  EXPECT_DOUBLE_EQ(bench::cpuBetween(a, 3.5, 3.9).wall_s, 0.0);  // no sample inside
  bench::ProcSeries b{"omnislam-features", 11, {{1.0, 0.0, 0, 0}, {2.0, 0.25, 0, 0}}};
  const auto by_name = bench::cpuByProgram({{10, a}, {11, b}}, 0.5, 3.5);
  ASSERT_EQ(by_name.size(), 1u);
  EXPECT_DOUBLE_EQ(by_name.at("omnislam-features").cpu_s, 1.25);
  EXPECT_DOUBLE_EQ(by_name.at("omnislam-features").wall_s, 2.0);
  EXPECT_DOUBLE_EQ(*bench::lastSampleOf({{10, a}, {11, b}}, "omnislam-features"), 4.0);
  EXPECT_FALSE(bench::lastSampleOf({{10, a}}, "omnislam-sim"));
}

TEST(BenchSlope, IsTheLeastSquaresSlopeInsideTheWindow) {
  std::vector<std::pair<double, double>> t_y;
  for (int i = 0; i <= 10; ++i) t_y.emplace_back(i, i < 5 ? 100.0 * i : 3.0 + 0.5 * i);
  EXPECT_NEAR(*bench::slopeBetween(t_y, 5.0, 10.0), 0.5, 1e-12);
  EXPECT_FALSE(bench::slopeBetween(t_y, 5.5, 5.9));                       // no point
  EXPECT_FALSE(bench::slopeBetween({{1.0, 2.0}, {1.0, 3.0}}, 0.0, 2.0));  // one time only
}

TEST(BenchWorldVariant, TruthRateIsAWholeMultipleOfTheImageRate) {
  EXPECT_DOUBLE_EQ(bench::truthRateFor(30.0), 60.0);
  EXPECT_DOUBLE_EQ(bench::truthRateFor(1.0), 50.0);
  EXPECT_DOUBLE_EQ(bench::truthRateFor(25.0), 50.0);
  EXPECT_DOUBLE_EQ(bench::truthRateFor(100.0), 100.0);
}

TEST(BenchWorldVariant, TheSportsHallAt30HzKeepsEverythingButTheRates) {
  const sim::World hall = config::loadWorld(std::string(OMNISLAM_SOURCE_DIR) + "/config/worlds/sports_hall.yaml");
  const sim::World w = bench::worldVariant(hall, 30.0, 0.0);
  EXPECT_DOUBLE_EQ(w.image_rate_hz, 30.0);
  EXPECT_DOUBLE_EQ(w.truth_rate_hz, 60.0);
  EXPECT_EQ(w.camera.intrinsics.width_px, 640);
  EXPECT_EQ(w.camera.intrinsics.height_px, 480);
  EXPECT_EQ(w.lights.size(), hall.lights.size());
  EXPECT_EQ(w.segments.size(), hall.segments.size());
  EXPECT_DOUBLE_EQ(bench::durationOf(w), bench::durationOf(hall));
}

TEST(BenchWorldVariant, APathDrivenBackAndForthLastsLongEnoughAndReturnsOnItself) {
  sim::World w;
  w.trajectory_options.start = {1.0, 2.0, 0.3};
  w.segments = {{sim::Segment::Kind::kStraight, 5.0, 0.0, 0.0},
                {sim::Segment::Kind::kArc, 0.0, 2.0, 1.2},
                {sim::Segment::Kind::kTurn, 0.0, 0.0, -0.7},
                {sim::Segment::Kind::kStraight, 3.0, 0.0, 0.0}};
  const double once = bench::durationOf(w);
  const sim::World longer = bench::worldVariant(w, 0.0, 2.5 * once);
  EXPECT_GE(bench::durationOf(longer), 2.5 * once);
  EXPECT_DOUBLE_EQ(longer.image_rate_hz, w.image_rate_hz);
  // out, half turn, back: 9 segments end where the robot started, facing the other way
  sim::World there_and_back = w;
  there_and_back.segments.assign(longer.segments.begin(), longer.segments.begin() + 9);
  const auto end =
      sim::Trajectory(there_and_back.trajectory_options, there_and_back.segments).at(bench::durationOf(there_and_back));
  EXPECT_NEAR(end.pose.x_m, 1.0, 1e-9);
  EXPECT_NEAR(end.pose.y_m, 2.0, 1e-9);
  EXPECT_NEAR(std::abs(wrapAngle(end.pose.theta_rad - 0.3)), kPi, 1e-9);
}
