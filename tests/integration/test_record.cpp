// omnislam-record stops in bounded time on a bus that stays busy: its stop-time drain ran until the
// bus was quiet, so in a flood it ignored SIGINT and SIGTERM (17 s after SIGINT in an audit) and a
// launcher's SIGKILL would have lost the last buffer and the report.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <thread>
#include <vector>

#include "omnislam/lcmio/log_reader.h"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

// Publishes 200-byte messages as fast as it can on `url` until `stop`, from two threads, so that
// the recorder never sees the bus run dry.
class Flood {
 public:
  explicit Flood(const std::string& url) {
    for (int k = 0; k < 2; ++k)
      threads_.emplace_back([this, url] {
        lcm::LCM bus(url);
        std::vector<uint8_t> data(200, 0x5a);
        while (bus.good() && !stop_.load()) bus.publish("FLOOD", data.data(), static_cast<unsigned>(data.size()));
      });
  }
  ~Flood() {
    stop_.store(true);
    for (auto& th : threads_) th.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::vector<std::thread> threads_;
};

}  // namespace

TEST(Record, StopsSoonAfterSigintWhileTheBusStaysBusy) {
  t::TempDir dir;
  const std::string url = t::privateUdpUrl(57), path = dir.file("flood.lcm");
  t::Child rec({t::binPath("omnislam-record"), "-f", path, "--url", url});
  ASSERT_TRUE(rec.waitForOutput("recording", 5)) << rec.output();
  t::RunResult r;
  double stop_s = 0;
  {
    Flood flood(url);
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));
    const auto t0 = std::chrono::steady_clock::now();
    rec.signal(SIGINT);
    r = rec.wait(5.0);  // the old recorder was still draining when the flood stopped
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
      << in_file << " events in the file; said:\n" << r.output;
}
