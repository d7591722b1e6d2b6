// omnislam-record stops in bounded time on a bus that stays busy: its stop-time drain does not wait
// for a quiet bus (in a flood that would ignore SIGINT and SIGTERM, and a launcher's SIGKILL would
// lose the last buffer and the report). And a SIGKILL loses at most the last flush interval, not
// everything buffered since the start.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <csignal>
#include <optional>
#include <thread>
#include <vector>

#include "omnislam/lcmio/log_reader.h"
#include "bus_util.h"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;

TEST(Record, StopsSoonAfterSigintWhileTheBusStaysBusy) {
  t::TempDir dir;
  const std::string url = t::privateUdpUrl(57), path = dir.file("flood.lcm");
  t::Child rec({t::binPath("omnislam-record"), "-f", path, "--url", url});
  ASSERT_TRUE(rec.waitForOutput("recording", 5)) << rec.output();
  t::RunResult r;
  double stop_s = 0;
  {
    t::BusFlood flood(url, 2, 60.0);
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));
    const auto t0 = std::chrono::steady_clock::now();
    rec.signal(SIGINT);
    r = rec.wait(5.0);  // a recorder that drains its whole queue would still be draining when the flood stops
    stop_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  EXPECT_FALSE(r.timed_out) << "still draining a busy bus 5 s after SIGINT:\n" << r.output;
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_LT(stop_s, 4.0) << r.output;  // a drain of 0.5 s, then flush and sync
  // The recording was flushed and closed: the events it reports are the events in the file.
  int64_t in_file = 0;
  lcmio::forEachEvent(path, [&](const lcmio::LogEvent&) { ++in_file; });
  EXPECT_GT(in_file, 0);
  EXPECT_NE(r.output.find("[record] " + std::to_string(in_file) + " events"), std::string::npos)
      << in_file << " events in the file; said:\n"
      << r.output;
}

// A recorder killed with SIGKILL (a launcher's last resort, the OOM killer, a crash) cannot flush
// at exit. It held up to 32 KiB in its buffer until the stop, so a slow bus (odometry at 50 Hz is
// about 2 KB/s) lost the last 15 s or, as here, everything. With the default flush interval the
// messages are in the file within about 0.5 s and survive the kill, complete and readable.
TEST(Record, ASigkillLosesAtMostTheLastFlushInterval) {
  t::TempDir dir;
  const std::string url = t::privateUdpUrl(58), path = dir.file("killed.lcm");
  t::Child rec({t::binPath("omnislam-record"), "-f", path, "--url", url});
  ASSERT_TRUE(rec.waitForOutput("recording", 5)) << rec.output();
  constexpr int kMessages = 40;  // 40 x 150 bytes: far less than the buffer
  {
    lcm::LCM bus(url);
    ASSERT_TRUE(bus.good());
    std::vector<uint8_t> data(150, 0x42);
    for (int i = 0; i < kMessages; ++i) {
      bus.publish("SLOW", data.data(), static_cast<unsigned>(data.size()));
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  // Wait for the events to reach the file (a deadline, not a timing bound): the recorder before
  // the periodic flush never wrote them before its stop.
  int64_t in_file = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < deadline) {
    in_file = 0;
    lcmio::forEachEvent(path, [&](const lcmio::LogEvent&) { ++in_file; });
    if (in_file >= kMessages) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  rec.signal(SIGKILL);
  const t::RunResult r = rec.wait(5.0);
  EXPECT_EQ(r.exit_code, 128 + SIGKILL) << r.output;
  in_file = 0;
  const lcmio::LogReadResult read = lcmio::forEachEvent(path, [&](const lcmio::LogEvent& e) {
    ++in_file;
    EXPECT_EQ(e.channel, "SLOW");
    EXPECT_EQ(e.data.size(), 150u);
  });
  EXPECT_EQ(in_file, kMessages) << "events in the file of the killed recorder";
  EXPECT_EQ(read.problem(path), std::nullopt) << *read.problem(path);
}
