// Soak (opt-in, label `soak`): the whole system live on the sports hall for ten times the default
// trajectory (the three loops driven ten times over, about 53 simulated minutes, 3200 frames), at
// speedup 25. What a long run must keep that the 320 s integration test cannot show:
// - every process stays up and every feature frame is answered;
// - no process's memory grows with time: the map is complete after the first lap, so the resident
//   memory of each process (sampled from /proc every 0.5 s) must level off (a leak of 1 kB per
//   frame is 3 MB over the run);
// - the SLAM error stays bounded while dead reckoning drifts: the last lap is scored like the first.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "omnislam/eval/metrics.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "eval_json.h"
#include "proc_util.h"
#include "slam_log.h"

using namespace omnislam;
namespace t = omnislam::testing;
namespace fs = std::filesystem;
using omnislam::testing::jsonNumber;

namespace {

constexpr int kLaps = 10;
constexpr int kUrlSalt = 29;

/// The sports hall world with its trajectory's segments repeated `laps` times (the trajectory is
/// closed: it ends at its start pose, so the repeats join up).
std::string repeatedHallWorld(int laps) {
  std::ifstream in(t::sourcePath("config/worlds/sports_hall.yaml"));
  std::vector<std::string> before, segments, after;
  std::string line;
  int part = 0;  // 0: before the segments, 1: inside, 2: after
  while (std::getline(in, line)) {
    if (part == 0) {
      before.push_back(line);
      if (line.find("segments:") != std::string::npos) part = 1;
    } else if (part == 1 && (line.rfind("    - ", 0) == 0 || line.rfind("    #", 0) == 0)) {
      segments.push_back(line);
    } else {
      part = 2;
      after.push_back(line);
    }
  }
  std::ostringstream out;
  for (const auto& l : before) out << l << "\n";
  for (int k = 0; k < laps; ++k)
    for (const auto& l : segments) out << l << "\n";
  for (const auto& l : after) out << l << "\n";
  return out.str();
}

/// Resident memory of every process that runs on one LCM URL (the launcher gives each child the
/// URL in LCM_DEFAULT_URL; the recorder gets it on its command line), sampled on a thread.
class MemoryMonitor {
 public:
  explicit MemoryMonitor(std::string url) : url_(std::move(url)), thread_([this] { loop(); }) {}
  ~MemoryMonitor() { stop(); }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  /// Per process (comm name and pid), its resident memory [kB], one sample per 0.5 s in time order.
  std::map<std::string, std::vector<long>> series() const {
    std::lock_guard<std::mutex> lock(mu_);
    return series_;
  }

 private:
  void loop() {
    while (!stop_) {
      std::error_code ec;
      for (const auto& e : fs::directory_iterator("/proc", ec)) {
        const std::string pid = e.path().filename().string();
        if (pid.empty() || !std::all_of(pid.begin(), pid.end(), ::isdigit)) continue;
        const std::string env = t::readFile(e.path() / "environ"), cmd = t::readFile(e.path() / "cmdline");
        if (env.find("LCM_DEFAULT_URL=" + url_) == std::string::npos && cmd.find(url_) == std::string::npos) continue;
        std::string comm = t::readFile(e.path() / "comm");
        if (!comm.empty() && comm.back() == '\n') comm.pop_back();
        if (comm.rfind("omnislam-", 0) != 0) continue;  // the processes of the system, not a shell
        std::istringstream status(t::readFile(e.path() / "status"));
        std::string l;
        while (std::getline(status, l))
          if (l.rfind("VmRSS:", 0) == 0) {
            const long kb = std::stol(l.substr(6));
            std::lock_guard<std::mutex> lock(mu_);
            series_[comm + " " + pid].push_back(kb);
          }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
    }
  }
  std::string url_;
  std::atomic<bool> stop_{false};
  mutable std::mutex mu_;
  std::map<std::string, std::vector<long>> series_;
  std::thread thread_;
};

/// Errors of the poses of `est` with utime in [from, to) against the truth.
eval::TrajectoryErrors errorsOver(const std::vector<eval::TimedPose>& est, const std::vector<eval::TimedPose>& truth,
                                  int64_t from, int64_t to) {
  std::vector<eval::TimedPose> part;
  for (const auto& p : est)
    if (p.utime >= from && p.utime < to) part.push_back(p);
  return eval::trajectoryErrors(eval::pairByTime(part, truth));
}

TEST(Soak, SportsHallTenLapsLive) {
  t::TempDir d;
  const std::string world = d.file("sports_hall_x10.yaml");
  std::ofstream(world) << repeatedHallWorld(kLaps);
  MemoryMonitor mem(t::privateUdpUrl(kUrlSalt));
  // As the full-system test: 10 s of wall time at speedup 25 before a stalled process counts as dead.
  t::LaunchedRun run("config/launch/sports_hall_slam.yaml", kUrlSalt,
                     {"world=" + world, "speedup=25", "odometry_only_after_s=250", "seed=3", "slam_seed=3"}, 900.0);
  mem.stop();
  ASSERT_EQ(run.result.exit_code, 0) << run.result.output;
  EXPECT_EQ(run.result.output.find("died"), std::string::npos) << run.result.output;
  const size_t num_frames = t::expectEveryFrameAnswered(run.log);
  size_t num_images = 0;  // every image the capture process published became a feature frame
  lcmio::forEachEvent(run.log, [&](const lcmio::LogEvent& e) { num_images += e.channel == channels::kOmniImage; });
  EXPECT_EQ(num_frames, num_images);
  EXPECT_GE(num_frames, static_cast<size_t>(kLaps * 319));  // a lap takes 319.9 s, one image a second

  // Memory: per process, the median resident memory of the last quarter of its samples against
  // that of the second quarter (after start-up and the first lap's mapping). A leak raises the whole
  // quarter. Peaks only follow the largest backlog in a queue, which depends on the machine's load
  // (7 queued images are 2 MB; a peak comparison failed once so, capture +4.6 MB), so they are
  // printed, not bounded.
  const auto series = mem.series();
  std::set<std::string> names;
  for (const auto& [proc, s] : series) {
    ASSERT_GE(s.size(), 40u) << proc << ": too few memory samples";
    const size_t q = s.size() / 4;
    const auto quarter = [&](size_t from, size_t to) { return std::vector<long>(s.begin() + from, s.begin() + to); };
    const auto median = [](std::vector<long> v) {
      std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
      return v[v.size() / 2];
    };
    const std::vector<long> q2 = quarter(q, 2 * q), q4 = quarter(3 * q, s.size());
    const long med2 = median(q2), med4 = median(q4);
    const long peak2 = *std::max_element(q2.begin(), q2.end()), peak4 = *std::max_element(q4.begin(), q4.end());
    std::cout << proc << ": resident memory median " << med2 / 1024.0 << " MB in the second quarter of the run, "
              << med4 / 1024.0 << " MB in the last (peaks " << peak2 / 1024.0 << " and " << peak4 / 1024.0 << " MB)\n";
    // 2 MB of allocator slack; a leak of 1 kB per frame adds 0.8 MB per quarter of the run.
    EXPECT_LE(med4, med2 + 2048) << proc << " grows over the run";
    names.insert(proc.substr(0, proc.find(' ')));
  }
  for (const char* p : {"omnislam-sim", "omnislam-captur", "omnislam-odomet", "omnislam-featur", "omnislam-slam"})
    EXPECT_TRUE(names.count(p)) << p << " was not seen by the memory monitor";  // comm is cut at 15 characters

  // The whole run against paper 000's bars, and the last lap against the first.
  const auto ev = t::run({t::binPath("omnislam-eval"), run.log, "--json", "--no-tum"}, 120);
  ASSERT_EQ(ev.exit_code, 0) << ev.output;
  std::cout << ev.output;
  t::expectHallMapWithinPaper000Bars(ev.output);
  const auto slam = t::timedPoses(run.log, channels::kSlamPose);
  const auto dr = t::deadReckoning(run.log, t::kSportsHallStartW);
  const auto truth = t::timedPoses(run.log, channels::kGroundTruthPose);
  ASSERT_FALSE(truth.empty());
  const int64_t t0 = truth.front().utime, lap_us = (truth.back().utime - t0) / kLaps;
  std::vector<eval::TrajectoryErrors> slam_lap, dr_lap;
  for (int k = 0; k < kLaps; ++k) {
    const int64_t from = t0 + k * lap_us, to = k + 1 == kLaps ? truth.back().utime + 1 : from + lap_us;
    slam_lap.push_back(errorsOver(slam, truth, from, to));
    dr_lap.push_back(errorsOver(dr, truth, from, to));
    std::cout << "lap " << k + 1 << ": SLAM ATE RMSE " << slam_lap[k].ate_rmse_m << " m, max " << slam_lap[k].ate_max_m
              << " m, heading max " << slam_lap[k].heading_max_rad << " rad; dead reckoning ATE RMSE "
              << dr_lap[k].ate_rmse_m << " m\n";
  }
  // Bounded: the last lap no worse than the first by more than the first lap's own error (the map is
  // built in the first lap, so the first lap is the harder one), and far better than dead reckoning.
  EXPECT_LE(slam_lap.back().ate_rmse_m, 2.0 * slam_lap.front().ate_rmse_m + 0.05);
  EXPECT_LT(slam_lap.back().ate_rmse_m, 0.5 * dr_lap.back().ate_rmse_m);
  // Heading, per lap: paper 000's bar of 5 deg on the maximum, on every lap. (Before the filter's
  // predictive association, seed 3 had one frame at 7.7 deg in lap 9: docs/results/slam-results.md, "Ten laps".)
  for (int k = 0; k < kLaps; ++k) {
    EXPECT_LE(slam_lap[k].heading_max_rad, 5.0 * kPi / 180.0) << "lap " << k + 1;
    EXPECT_LE(slam_lap[k].heading_rmse_rad, 0.087) << "lap " << k + 1;
  }
}

}  // namespace
