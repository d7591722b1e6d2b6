// omnislam-record: records every LCM message of a bus into a standard LCM log file (the format of
// lcm-logger, replayable with lcm-logplayer). Unlike lcm-logger 1.3.1, whose subscription keeps
// LCM's default queue of 30 messages and silently drops when it is starved of CPU, it queues up
// to --queue messages, so a busy machine delays the recording instead of losing it.
#include <CLI/CLI.hpp>

#include <lcm/lcm-cpp.hpp>

#include <iostream>

#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/signals.h"

namespace {

struct Recorder {
  lcm::LogFile* log = nullptr;
  int64_t events = 0, bytes = 0, failures = 0;
  // Through LCM's C API: its lcm_subscribe returns NULL for a regex it cannot compile, where the
  // C++ wrapper returns an object whose use then crashes.
  static void onC(const lcm_recv_buf_t* rbuf, const char* channel, void* self) {
    static_cast<Recorder*>(self)->on(rbuf, channel);
  }
  void on(const lcm_recv_buf_t* rbuf, const std::string& channel) {
    lcm::LogEvent ev;
    ev.eventnum = events;
    ev.timestamp = rbuf->recv_utime;  // the log's own receive time, as lcm-logger writes it
    ev.channel = channel;
    ev.datalen = static_cast<int32_t>(rbuf->data_size);
    ev.data = rbuf->data;
    if (log->writeEvent(&ev) != 0) {
      ++failures;
      return;
    }
    ++events;
    bytes += rbuf->data_size;
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-record: records an LCM bus into a log file without silent drops"};
  std::string url, path, channels = ".*";
  int queue = 20000;
  cli.add_option("-f,--file", path, "output log file (overwritten)")->required();
  cli.add_option("--url", url, "LCM URL (default: $LCM_DEFAULT_URL)");
  cli.add_option("-c,--channels", channels, "channel regex (anchored, as in LCM)");
  cli.add_option("--queue", queue, "messages queued before LCM drops")->check(CLI::Range(30, 10'000'000));
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  return omnislam::app::runMain("omnislam-record", [&]() -> int {
    // Everything that can be refused is checked before the file is opened (and so emptied).
    lcm::LCM bus(omnislam::app::lcmUrl(url));
    if (!bus.good())
      throw std::invalid_argument("--url: cannot start LCM on '" + omnislam::app::lcmUrl(url) +
                                  "' (check the URL and multicast routing)");
    Recorder rec;
    lcm_subscription_t* sub = lcm_subscribe(bus.getUnderlyingLCM(), channels.c_str(), &Recorder::onC, &rec);
    if (!sub) throw std::invalid_argument("--channels: LCM cannot compile the regular expression '" + channels + "'");
    lcm_subscription_set_queue_capacity(sub, queue);
    lcm::LogFile log(path, "w");
    if (!log.good()) throw std::invalid_argument("--file: cannot write '" + path + "'");
    omnislam::lcmio::installStopHandlers();
    rec.log = &log;
    std::cerr << "[record] recording '" << channels << "' into " << path << std::endl;
    while (!omnislam::lcmio::stopRequested()) bus.handleTimeout(100);
    // Drain what has already arrived, then close the file (flushes).
    while (bus.handleTimeout(0) > 0) {
    }
    std::cerr << "[record] " << rec.events << " events, " << rec.bytes / 1e6 << " MB"
              << (rec.failures ? ", " + std::to_string(rec.failures) + " WRITE FAILURES" : "") << std::endl;
    return rec.failures ? omnislam::app::kFailure : omnislam::app::kOk;
  });
}
