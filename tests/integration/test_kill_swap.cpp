// The SLAM process survives its inputs changing under it (issue 5, kill and swap tests): the
// whole sports-hall system runs as separate processes on a private LCM URL; at 230 s of simulated
// time (loop 2: every light has been mapped in loop 1, so the recovery is a re-association) the
// features process is killed (SIGKILL) and restarted 10 s later; at 280 s it is replaced
// by a second detector configuration (another threshold and connectivity): the second one starts,
// and once it reports running the first one stops (a short overlap: the SLAM process refuses the
// duplicate frames by utime). The SLAM
// process is never touched until the end, when SIGTERM must make it save its map atomically.
// Checks: SLAM_POSE keeps coming during the outage (odometry-only poses, input_seq -1) by the
// liveness rule, frames are answered again after it, the second configuration alone feeds the SLAM
// process once the first one stops, the final map and path meet paper 000's bars, and the saved map
// then localises a replay of the same recording with the map held fixed (localisation-only mode).
// Nothing here depends on how fast a process starts or how loaded the machine is (CI runs it beside
// other tests on two cores): the recording says what each process received and when, in log order.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <utility>

#include "bus_util.h"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/process_status_t.hpp"
#include "eval_json.h"
#include "proc_util.h"
#include "slam_log.h"

using namespace omnislam;
namespace t = omnislam::testing;
using omnislam::testing::jsonNumber;

namespace {

/// The second detector configuration: the shipped one with another threshold and connectivity
/// (and the world path made absolute, since the copy lives in a temporary folder).
std::string writeDetectorB(const t::TempDir& dir) {
  std::string text = t::readFile(t::sourcePath("config/features/ceiling_lights.yaml"));
  text = std::regex_replace(text, std::regex("threshold_grey: *[0-9.]+"), "threshold_grey: 70");
  text = std::regex_replace(text, std::regex("connectivity: *8"), "connectivity: 4");
  text = std::regex_replace(text, std::regex("world: *\\.\\./worlds/"), "world: " + t::sourcePath("config/worlds/"));
  const std::string path = dir.file("ceiling_lights_b.yaml");
  std::ofstream(path) << text;
  return path;
}

TEST(KillSwap, SlamCarriesOnThroughAKilledAndASwappedFeaturesProcess) {
  t::TempDir dir;
  const std::string url = t::privateUdpUrl(15);
  const std::string world = t::sourcePath("config/worlds/sports_hall.yaml");
  const std::string feat_a = t::sourcePath("config/features/ceiling_lights.yaml");
  const std::string feat_b = writeDetectorB(dir);
  const std::string log = dir.file("run.lcm"), map = dir.file("map.yaml");

  t::Child rec({t::binPath("omnislam-record"), "-f", log, "--url", url});
  t::Child cap({t::binPath("omnislam-capture"), "--source", "sim", "--world", world, "--seed", "3", "--url", url});
  t::Child odo({t::binPath("omnislam-odometry"), "--source", "sim", "--world", world, "--seed", "3", "--url", url});
  auto features = std::make_unique<t::Child>(
      std::vector<std::string>{t::binPath("omnislam-features"), "--config", feat_a, "--url", url});
  t::Child slam({t::binPath("omnislam-slam"), "--config", t::sourcePath("config/slam/sports_hall.yaml"), "--seed", "3",
                 "--url", url, "--save-map", map});
  t::Child sim({t::binPath("omnislam-sim"), "--world", world, "--speedup", "10", "--url", url, "--wait-for",
                "capture,odometry,features,slam", "--wait-timeout", "60"});

  // Follow the simulated clock on the bus.
  lcm::LCM bus(url);
  ASSERT_TRUE(bus.good());
  struct Clock {
    int64_t first = -1, last = -1;
    void onOdometry(const lcm::ReceiveBuffer*, const std::string&, const odometry_t* m) {
      if (first < 0) first = m->utime;
      last = m->utime;
    }
  } clock;
  bus.subscribe(channels::kOdometry, &Clock::onOdometry, &clock);
  const auto simSeconds = [&] { return clock.first < 0 ? -1.0 : (clock.last - clock.first) * 1e-6; };
  ASSERT_TRUE(t::handleUntil(
      bus, [&] { return simSeconds() >= 230.0; }, 120.0))
      << sim.output();
  features->signal(SIGKILL);
  features->wait(5);
  ASSERT_TRUE(t::handleUntil(
      bus, [&] { return simSeconds() >= 240.0; }, 60.0));
  features = std::make_unique<t::Child>(
      std::vector<std::string>{t::binPath("omnislam-features"), "--config", feat_a, "--url", url});
  ASSERT_TRUE(t::handleUntil(
      bus, [&] { return simSeconds() >= 280.0; }, 60.0));
  // Swap: the second configuration starts, then the first one stops.
  t::Child features_b({t::binPath("omnislam-features"), "--config", feat_b, "--url", url, "--name", "features_b"});
  struct Status {
    bool b_running = false;
    void onStatus(const lcm::ReceiveBuffer*, const std::string&, const process_status_t* m) {
      if (m->name == "features_b" && m->state == process_status_t::STATE_RUNNING) b_running = true;
    }
  } status;
  bus.subscribe(channels::kProcessStatus, &Status::onStatus, &status);
  ASSERT_TRUE(t::handleUntil(
      bus, [&] { return status.b_running; }, 30.0))
      << features_b.output();
  features->signal(SIGINT);
  const auto fa = features->wait(10);
  EXPECT_EQ(fa.exit_code, 0) << fa.output;
  const auto s = sim.wait(120);
  ASSERT_EQ(s.exit_code, 0) << s.output;
  t::handleFor(bus, 3.0);  // the last frames reach the SLAM process
  EXPECT_TRUE(slam.alive()) << slam.output();
  slam.signal(SIGTERM);
  const auto sr = slam.wait(20);
  EXPECT_EQ(sr.exit_code, 0) << sr.output;
  EXPECT_NE(sr.output.find("map saved"), std::string::npos) << sr.output;
  for (t::Child* c : {&features_b, &cap, &odo, &rec}) c->signal(SIGINT);
  for (t::Child* c : {&features_b, &cap, &odo, &rec}) EXPECT_EQ(c->wait(20).exit_code, 0);

  // What happened, read from the recording in log order. The recorder and the SLAM process receive
  // the same multicast packets in the same order, so a message logged before a SLAM_POSE had reached
  // the SLAM process when it published that pose. Every check below follows from a rule of the
  // software, not from how fast the processes start or how busy the machine is: at 10 x a process
  // that takes 1 s of wall time to start misses 10 frames, and 30 ms of latency is 0.3 s of
  // simulated time. Those load-dependent figures are printed, not bounded.
  const int64_t start = clock.first;
  const auto sim_s = [&](int64_t utime) { return (utime - start) * 1e-6; };

  // Frames, split into the three features processes by their own sequence numbers: each process
  // numbers its frames 0, 1, 2, ... (the first detector, its restart, the second configuration).
  struct Frame {
    int64_t utime, seq;
    int stream;
    int64_t newest_odometry_at_arrival;
  };
  std::vector<Frame> frames;
  std::vector<int64_t> stream_last_seq;
  int unassigned = 0;
  // The liveness rule (docs/user/slam-process.md, SlamDriver::maybePredict): the first odometry-only pose
  // comes once odometry_only_after_s (3 s, the shipped default) of odometry time has passed since
  // the last frame *arrived*, i.e. since the newer of its utime and the newest odometry utime at its
  // arrival (a late frame still shows the features process alive); then one every
  // odometry_only_period_s (1 s). The slack is five odometry periods (50 Hz), for odometry messages
  // the SLAM process may drop.
  constexpr int64_t kAfterUs = 3'000'000, kPeriodUs = 1'000'000, kSlackUs = 100'000;
  int64_t newest_odometry = 0, alive_since = 0, max_silence_us = 0, max_latency_us = 0;
  std::optional<pose_t> prev;
  std::set<std::pair<int64_t, int64_t>> answered;  // (utime, input_seq) of the frames answered
  std::set<int64_t> answered_utime, odometry_only_utime;
  int onsets = 0, odo_only_in_gap = 0, frames_after = 0, answers = 0;
  std::size_t n_poses = 0;
  lcmio::forEachEvent(log, [&](const lcmio::LogEvent& ev) {
    if (ev.channel == channels::kOdometry) {
      if (auto m = lcmio::decodeAs<odometry_t>(ev)) newest_odometry = std::max(newest_odometry, m->utime);
    } else if (ev.channel == channels::kOmniFeatures) {
      const auto m = lcmio::decodeAs<features_t>(ev);
      if (!m) return;
      alive_since = std::max({alive_since, m->utime, newest_odometry});
      int stream = -1;
      // The first frame logged starts the first stream whatever its number: the simulator does not
      // wait for the recorder, which may miss the first frames on a loaded machine.
      if (m->seq == 0 || stream_last_seq.empty()) {
        stream = static_cast<int>(stream_last_seq.size());
        stream_last_seq.push_back(m->seq);
      } else {
        for (std::size_t k = 0; k < stream_last_seq.size(); ++k)
          if (stream_last_seq[k] == m->seq - 1) stream = static_cast<int>(k);
        if (stream >= 0) stream_last_seq[static_cast<std::size_t>(stream)] = m->seq;
      }
      if (stream < 0) ++unassigned;
      frames.push_back({m->utime, m->seq, stream, newest_odometry});
    } else if (ev.channel == channels::kSlamPose) {
      const auto p = lcmio::decodeAs<pose_t>(ev);
      if (!p) return;
      ++n_poses;
      const double ts = sim_s(p->utime);
      if (p->input_seq < 0 && ts > 230.0 && ts < 245.0) ++odo_only_in_gap;
      if (p->input_seq < 0) odometry_only_utime.insert(p->utime);
      if (p->input_seq >= 0) {
        ++answers;
        answered.insert({p->utime, p->input_seq});
        answered_utime.insert(p->utime);
        if (ts > 245.0) ++frames_after;
      }
      if (prev) {
        const int64_t gap = p->utime - prev->utime;
        max_silence_us = std::max(max_silence_us, gap);
        if (p->input_seq < 0 && prev->input_seq < 0) {
          EXPECT_LE(gap, kPeriodUs + kSlackUs) << "odometry-only poses every second, at " << sim_s(prev->utime) << " s";
        } else if (p->input_seq < 0) {
          ++onsets;
          max_latency_us = std::max(max_latency_us, alive_since - prev->utime);
          EXPECT_LE(p->utime, std::max(alive_since, prev->utime) + kAfterUs + kSlackUs)
              << "first odometry-only pose after the frame answered at " << sim_s(prev->utime) << " s: it came "
              << (p->utime - alive_since) * 1e-6 << " s after the last frame arrived";
        }
      }
      prev = *p;
    }
  });
  std::cout << "odometry-only poses in the outage: " << odo_only_in_gap
            << ", frames answered after it: " << frames_after << ", odometry-only onsets: " << onsets
            << ", largest gap between SLAM_POSEs: " << max_silence_us * 1e-6
            << " s, largest frame latency at an onset: " << max_latency_us * 1e-6 << " s of simulated time\n";
  ASSERT_GT(n_poses, 250u);
  EXPECT_GE(onsets, 1) << "the outage starts odometry-only poses";
  // From 3 s after the last frame (233 s + its latency) to the restarted process's first frame
  // (240 s + the same latency at least): one a second, whatever the latency.
  EXPECT_GE(odo_only_in_gap, 6) << "one per second from 3 s after the last frame";

  // Three processes fed the bus, each numbering its frames without a gap.
  ASSERT_EQ(stream_last_seq.size(), 3u) << "the first detector, its restart and the second configuration";
  EXPECT_EQ(unassigned, 0) << "frames that continue no process's numbering";
  // Every image has a frame, from one process or another, except in the outage: the only hole in
  // the frames' times runs from the killed process's last frame to its restart's first frame, which
  // is after 240 s (the restart began once the test's clock, never ahead of the simulator, said so).
  // Per features process (stream): its first and last frame's utime and its number of frames.
  struct Extent {
    int64_t first = INT64_MAX, last = 0;
    int frames = 0;
  };
  std::vector<Extent> extent(stream_last_seq.size());
  ASSERT_GE(frames.size(), 2u) << "no OMNI_FEATURES recorded";
  std::set<int64_t> frame_utimes;
  for (const Frame& f : frames) {
    frame_utimes.insert(f.utime);
    if (f.stream < 0) continue;
    Extent& e = extent[static_cast<std::size_t>(f.stream)];
    e.first = std::min(e.first, f.utime);
    e.last = std::max(e.last, f.utime);
    ++e.frames;
  }
  const int64_t last_killed = extent[0].last, first_restarted = extent[1].first;
  std::cout << "outage: last frame of the killed process at " << sim_s(last_killed)
            << " s, first frame of its restart at " << sim_s(first_restarted) << " s\n";
  EXPECT_GE(sim_s(first_restarted), 240.0);
  int holes = 0;
  for (auto it = std::next(frame_utimes.begin()); it != frame_utimes.end(); ++it) {
    const int64_t before = *std::prev(it);
    if (*it - before <= 1'500'000) continue;  // images at 1 Hz
    ++holes;
    EXPECT_TRUE(before == last_killed && *it == first_restarted)
        << "a hole in the frames from " << sim_s(before) << " s to " << sim_s(*it) << " s";
  }
  EXPECT_EQ(holes, 1) << "the outage, and nothing else";

  // Every image is answered, once (in the swap's overlap the duplicate of an image is refused by
  // its utime), before the outage and after it, except a frame that reached the SLAM process after
  // an odometry-only step had passed its time: it is dropped behind the prediction, by the rule.
  // That step has a utime at or after the frame's and at or before the newest odometry when the
  // frame arrived (the SLAM process handles the messages in the order they arrive).
  int behind = 0;
  for (const int64_t u : frame_utimes) {
    if (answered_utime.count(u)) continue;
    bool was_behind = false;
    for (const Frame& f : frames)
      if (f.utime == u) {
        const auto step = odometry_only_utime.lower_bound(u);
        was_behind = was_behind || (step != odometry_only_utime.end() && *step <= f.newest_odometry_at_arrival);
      }
    behind += was_behind ? 1 : 0;
    EXPECT_TRUE(was_behind) << "the frame of " << sim_s(u) << " s was never answered";
  }
  std::cout << "frames dropped behind an odometry-only step: " << behind << "\n";
  EXPECT_EQ(answers, static_cast<int>(answered_utime.size())) << "an image answered twice";

  // The swap: once the first detector stopped, the second configuration alone fed the SLAM process
  // to the end of the run, and its frames were answered as its own (every one, by the check above,
  // unless dropped behind a prediction).
  const int64_t last_of_first = extent[1].last;
  const int b_frames = extent[2].frames;
  int b_alone = 0, b_alone_answered = 0;
  for (const Frame& f : frames)
    if (f.stream == 2 && f.utime > last_of_first) {
      ++b_alone;
      const bool as_its_own = answered.count({f.utime, f.seq}) > 0;
      b_alone_answered += as_its_own ? 1 : 0;
      if (answered_utime.count(f.utime)) {
        EXPECT_TRUE(as_its_own) << "the frame of " << sim_s(f.utime) << " s";
      }
    }
  std::cout << "second configuration: " << b_frames << " frames, " << b_alone << " after the first one stopped, "
            << b_alone_answered << " of them answered\n";
  EXPECT_GE(b_alone_answered, 1) << "the first detector stopped before the run ended";
  EXPECT_EQ(frames.back().stream, 2) << "the run's last frame came from the second configuration";
  EXPECT_EQ(*frame_utimes.rbegin(), frames.back().utime);
  // Its own status agrees: it reported every frame it published.
  int64_t b_out = 0;
  for (const auto& st : lcmio::readChannel<process_status_t>(log, channels::kProcessStatus))
    if (st.name == "features_b") b_out = std::max(b_out, st.messages_out);
  EXPECT_EQ(b_out, b_frames);

  // The run finishes within paper 000's bars.
  const auto ev = t::run({t::binPath("omnislam-eval"), log, "--json", "--no-tum"}, 60);
  ASSERT_EQ(ev.exit_code, 0) << ev.output;
  std::cout << ev.output;
  t::expectHallMapWithinPaper000Bars(ev.output);

  // The saved map: complete and atomic (no temporary left), and it localises a replay of the same
  // recording with the map fixed: every answered frame's map is the saved one, no landmark added.
  const std::string saved = t::readFile(map);
  EXPECT_NE(saved.find("format: omnislam-map"), std::string::npos);
  std::map<int64_t, Eigen::Vector3d> saved_landmarks;  // id -> position_m, as written (%.17g)
  for (std::size_t p = saved.find("- {id:"); p != std::string::npos; p = saved.find("- {id:", p + 1)) {
    const int64_t id = std::strtoll(saved.c_str() + p + 6, nullptr, 10);
    const char* s = saved.c_str() + saved.find("position_m: [", p) + 13;
    Eigen::Vector3d x;
    for (int i = 0; i < 3; ++i) {
      char* end = nullptr;
      x(i) = std::strtod(s, &end);
      s = end + 1;  // past ','
    }
    saved_landmarks[id] = x;
  }
  EXPECT_EQ(saved_landmarks.size(), 16u) << saved;
  for (const auto& e : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().string().find(".tmp."), std::string::npos) << e.path();
  const std::string out = dir.file("localise.lcm");
  const auto loc =
      t::run({t::binPath("omnislam-slam"), "--config", t::sourcePath("config/slam/sports_hall.yaml"), "--seed", "4",
              "--replay", log, "--out", out, "--load-map", map, "--localise", "--no-progress"},
             120);
  ASSERT_EQ(loc.exit_code, 0) << loc.output;
  const auto loc_maps = lcmio::readChannel<map_t>(out, channels::kSlamMap);
  ASSERT_GE(loc_maps.size(), 10u) << loc.output;
  for (const auto& m : loc_maps) {
    ASSERT_EQ(m.num_landmarks, 16);
    EXPECT_EQ(m.num_candidates, 0);
    for (const auto& l : m.landmarks) {
      const auto it = saved_landmarks.find(l.id);
      ASSERT_NE(it, saved_landmarks.end()) << "landmark " << l.id << " is not in the saved map";
      EXPECT_EQ(Eigen::Vector3d(l.position_m[0], l.position_m[1], l.position_m[2]), it->second) << "landmark " << l.id;
    }
  }
  const auto ev2 = t::run({t::binPath("omnislam-eval"), out, "--json", "--no-tum"}, 60);
  ASSERT_EQ(ev2.exit_code, 0) << ev2.output;
  std::cout << "localisation only in the saved map: " << ev2.output;
  EXPECT_EQ(jsonNumber(ev2.output, "landmarks_spurious"), 0) << ev2.output;
  EXPECT_LE(jsonNumber(ev2.output, "ate_rmse_m"), jsonNumber(ev.output, "ate_rmse_m") + 0.1) << ev2.output;
}

}  // namespace
