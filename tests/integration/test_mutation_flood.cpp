// Every process of the pipeline under a flood of mutated messages: copies of a real recording's
// messages with bits flipped, whole bytes or aligned fields set to extreme values (counts of 2^31 - 1,
// doubles of 1e300), truncated, extended, sent on another channel, or replaced by garbage, mixed
// with the recording itself in order. Each process must stay up, count what it refused, and stop
// cleanly on SIGINT with what it computed saved. The first such flood (a throw-away program) found
// a seq corrupted to 2^62 overflowing the gap counter, which UBSan stopped four processes on.
// Seeded: the same messages every run.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/decode.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/process_status_t.hpp"
#include "bus_util.h"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

struct Message {
  std::string channel;
  std::vector<uint8_t> bytes;
};

/// The mutations, each a different way a message can be damaged on the way.
class Mutator {
 public:
  explicit Mutator(uint64_t seed) : rng_(seed) {}
  size_t below(size_t n) { return n == 0 ? 0 : std::uniform_int_distribution<size_t>(0, n - 1)(rng_); }
  double unit() { return std::uniform_real_distribution<double>(0.0, 1.0)(rng_); }

  /// A damaged copy of `m` (or `m` itself), with the kind of damage in *kind. `others` supplies
  /// payloads of other channels.
  Message mutate(const Message& m, const std::vector<Message>& others, std::string* kind) {
    Message out = m;
    std::vector<uint8_t>& b = out.bytes;
    // The fields sit in the first few hundred bytes (after the 8-byte fingerprint); an image's
    // pixels after them are hit only by the flips that land anywhere.
    const size_t head = std::min<size_t>(b.size(), 300);
    const double r = unit();
    if (r < 0.30 && b.size() > 8) {
      *kind = "flip";
      for (size_t i = 0, n = 1 + below(8); i < n; ++i) {
        const size_t at = unit() < 0.8 ? 8 + below(head - 8) : below(b.size());
        b[at] ^= static_cast<uint8_t>(1u << below(8));
      }
    } else if (r < 0.40 && head > 8) {
      *kind = "byte";
      b[8 + below(head - 8)] = static_cast<uint8_t>(below(256));
    } else if (r < 0.48) {
      *kind = "truncate";
      b.resize(below(b.size() + 1));
    } else if (r < 0.53) {
      *kind = "append";
      for (size_t i = 0, n = 1 + below(64); i < n; ++i) b.push_back(static_cast<uint8_t>(below(256)));
    } else if (r < 0.58) {
      *kind = "cross";
      b = others[below(others.size())].bytes;
    } else if (r < 0.61) {
      *kind = "garbage";
      b.resize(below(2000));
      for (auto& x : b) x = static_cast<uint8_t>(below(256));
    } else if (r < 0.66 && b.size() >= 16) {
      *kind = "double";  // a big-endian double field set to an extreme value
      static const double kValues[] = {1e300, -1e300, 1e-300, -0.0, 1e18, -1e18, 3.2e9, 1e154};
      const double v = kValues[below(std::size(kValues))];
      uint64_t bits;
      std::memcpy(&bits, &v, 8);
      const size_t at = 8 + below(head - 15);
      for (int i = 0; i < 8; ++i) b[at + i] = static_cast<uint8_t>(bits >> (56 - 8 * i));
    } else if (r < 0.70 && b.size() >= 12) {
      *kind = "int";  // a big-endian int32 field (a count, a size) set to an extreme value
      static const uint32_t kValues[] = {0x7fffffffu, 0x80000000u, 0xffffffffu, 0u, 4096u, 4097u, 65536u, 100000u};
      const uint32_t v = kValues[below(std::size(kValues))];
      const size_t at = 8 + below(head - 11);
      for (int i = 0; i < 4; ++i) b[at + i] = static_cast<uint8_t>(v >> (24 - 8 * i));
    } else {
      *kind = "valid";
    }
    return out;
  }

 private:
  std::mt19937_64 rng_;
};

struct Proc {
  std::string name;
  std::unique_ptr<t::Child> child;
};

TEST(MutationFlood, EveryProcessStaysUpCountsWhatItRefusesAndStopsCleanly) {
  // A short real recording of the sports hall with SLAM: every channel of the contract but the
  // 0.2 labels (their type is covered by the decode fuzz test).
  t::LaunchedRun rec("config/launch/sports_hall_slam.yaml", 21, {"speedup=10", "duration=8"}, 120.0);
  ASSERT_EQ(rec.result.exit_code, 0) << rec.result.output;
  std::vector<Message> source;
  lcmio::forEachEvent(rec.log, [&](const lcmio::LogEvent& ev) {
    if (ev.channel.rfind("LCM_", 0) != 0) source.push_back({ev.channel, ev.data});
  });
  ASSERT_GT(source.size(), 500u);
  std::vector<size_t> images, statuses;
  for (size_t i = 0; i < source.size(); ++i) {
    if (source[i].channel == channels::kOmniImage) images.push_back(i);
    if (source[i].channel == channels::kProcessStatus) statuses.push_back(i);
  }
  ASSERT_FALSE(images.empty());
  ASSERT_FALSE(statuses.empty());

  const std::string url = t::privateUdpUrl(22);
  t::TempDir dir;
  const std::string world = t::sourcePath("config/worlds/sports_hall.yaml");
  std::vector<Proc> procs;
  auto start = [&](const std::string& name, std::vector<std::string> argv) {
    argv.insert(argv.end(), {"--url", url});
    procs.push_back({name, std::make_unique<t::Child>(argv)});
  };
  start("features",
        {t::binPath("omnislam-features"), "--config", t::sourcePath("config/features/ceiling_lights.yaml")});
  start("lines", {t::binPath("omnislam-features"), "--config", t::sourcePath("config/features/room_lines.yaml"),
                  "--name", "lines"});
  start("slam", {t::binPath("omnislam-slam"), "--config", t::sourcePath("config/slam/sports_hall.yaml"), "--save-map",
                 dir.file("map.yaml")});
  start("viewer", {t::binPath("omnislam-viewer"), "--headless", "--out-dir", dir.file("view"), "--every", "0"});
  start("capture", {t::binPath("omnislam-capture"), "--source", "sim", "--world", world});
  start("odometry", {t::binPath("omnislam-odometry"), "--source", "sim", "--world", world});
  start("sim", {t::binPath("omnislam-sim"), "--world", world, "--wait-for", "nobody", "--wait-timeout", "120"});

  // Wait until every process has announced itself (each publishes PROCESS_STATUS once subscribed).
  lcm::LCM bus(url);
  ASSERT_TRUE(bus.good());
  std::map<std::string, process_status_t> status;
  // Only our processes' own statuses: the flood also sends damaged copies of the recording's.
  std::map<int64_t, std::string> ours;
  for (const auto& p : procs) ours[p.child->pid()] = p.name;
  struct Sink {
    std::map<std::string, process_status_t>* status;
    const std::map<int64_t, std::string>* ours;
    void on(const lcm::ReceiveBuffer* rb, const std::string&) {
      process_status_t st;
      if (lcmio::decode(rb->data, rb->data_size, st)) return;
      const auto it = ours->find(st.pid);
      if (it != ours->end() && it->second == st.name) (*status)[st.name] = st;
    }
  } sink{&status, &ours};
  bus.subscribe(channels::kProcessStatus, &Sink::on, &sink);
  const std::vector<std::string> names{"features", "lines", "slam", "viewer", "capture", "odometry", "sim"};
  auto allSeen = [&] {
    for (const auto& n : names)
      if (!status.count(n)) return false;
    return true;
  };
  ASSERT_TRUE(t::handleUntil(bus, allSeen, 30.0)) << "not every process started";

  // First the recording's truth as it was, the simulator's part: capture, odometry, features and
  // SLAM make the rest, so that they hold a real state (a SLAM map to save) when the damage comes.
  int slam_poses = 0;
  struct PoseCount {
    int* n;
    void on(const lcm::ReceiveBuffer*, const std::string&) { ++*n; }
  } pose_count{&slam_poses};
  bus.subscribe(channels::kSlamPose, &PoseCount::on, &pose_count);
  for (const Message& m : source) {
    if (m.channel != channels::kGroundTruthPose && m.channel != channels::kGroundTruthMap) continue;
    bus.publish(m.channel, m.bytes.data(), static_cast<unsigned>(m.bytes.size()));
    std::this_thread::sleep_for(std::chrono::microseconds(2000));
  }
  ASSERT_TRUE(t::handleUntil(
      bus, [&] { return slam_poses > 0; }, 10.0))
      << "the SLAM process answered no frame";

  // The flood: 4000 messages, 60 % the recording in order (so the processes have a real state to
  // corrupt), 40 % drawn at random; each message mutated (or not) as above. Images are paced.
  Mutator mut(20261124);
  std::map<std::string, int> kinds;
  size_t in_order = 0;
  for (int k = 0; k < 4000; ++k) {
    // Every 20th message an image or a status, which the recording holds few of (1 Hz), so that the
    // features processes and the simulator (a status listener) get their share of damage.
    const std::vector<size_t>& rare = k % 40 == 0 ? images : statuses;
    const Message& m = k % 20 == 0        ? source[rare[mut.below(rare.size())]]
                       : mut.unit() < 0.6 ? source[in_order++ % source.size()]
                                          : source[mut.below(source.size())];
    std::string kind;
    const Message out = mut.mutate(m, source, &kind);
    ++kinds[kind];
    bus.publish(out.channel, out.bytes.data(), static_cast<unsigned>(out.bytes.size()));
    std::this_thread::sleep_for(std::chrono::microseconds(out.bytes.size() > 100000 ? 10000 : 1500));
    if (k % 200 == 0) bus.handleTimeout(0);
  }
  for (const auto& [kind, n] : kinds) std::cout << "[ flood ] " << kind << " " << n << "\n";
  EXPECT_GT(kinds["flip"], 900);
  EXPECT_GT(kinds["valid"], 900);

  // Everyone still up, and each still reports: a fresh status after the flood, with the damage counted.
  for (auto& p : procs) EXPECT_TRUE(p.child->alive()) << p.name << " died:\n" << p.child->output();
  status.clear();
  t::handleUntil(bus, allSeen, 5.0);
  for (const auto& n : names) {
    ASSERT_TRUE(status.count(n)) << n << " stopped reporting:\n";
    const process_status_t& st = status[n];
    std::cout << "[ flood ] " << n << ": in " << st.messages_in << ", decode errors " << st.decode_errors
              << ", rejected " << st.rejected_inputs << "\n";
    EXPECT_GT(st.decode_errors + st.rejected_inputs, 0) << n << " saw no damage: the flood did not reach it";
  }

  // SIGINT: each stops cleanly; the SLAM process saves its map and the viewer its final view.
  for (auto& p : procs) p.child->signal(SIGINT);
  for (auto& p : procs) {
    const auto r = p.child->wait(20.0);
    EXPECT_FALSE(r.timed_out) << p.name << " did not stop on SIGINT:\n" << r.output;
    EXPECT_EQ(r.exit_code, 0) << p.name << ":\n" << r.output;
    EXPECT_EQ(r.output.find("fatal"), std::string::npos) << p.name << ":\n" << r.output;
  }
  const std::string slam_out = procs[2].child->output();
  EXPECT_TRUE(std::filesystem::exists(dir.file("map.yaml")))
      << slam_out.substr(slam_out.size() > 3000 ? slam_out.size() - 3000 : 0);
  EXPECT_TRUE(std::filesystem::exists(dir.file("view/final.png")));
}

}  // namespace
