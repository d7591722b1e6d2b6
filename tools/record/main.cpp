// omnislam-record: records every LCM message of a bus into a standard LCM log file (the format of
// lcm-logger, replayable with lcm-logplayer). Unlike lcm-logger 1.3.1, whose subscription keeps
// LCM's default queue of 30 messages and silently drops when it is starved of CPU, it queues up
// to --queue messages, so a busy machine delays the recording instead of losing it. It hands
// what it has recorded to the operating system every --flush-interval-s, so a SIGKILL or a crash
// of the recorder loses at most that much (a SIGINT or SIGTERM loses nothing).
#include <CLI/CLI.hpp>

#include <lcm/lcm-cpp.hpp>

#include <sys/statvfs.h>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <optional>
#include <stdexcept>

#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/lcmio/signals.h"

namespace {

struct Recorder {
  omnislam::lcmio::LogWriter* log = nullptr;
  int64_t failures = 0;
  std::string first_failure;
  // Through LCM's C API: its lcm_subscribe returns NULL for a regex it cannot compile, where the
  // C++ wrapper returns an object whose use then crashes.
  static void onC(const lcm_recv_buf_t* rbuf, const char* channel, void* self) {
    static_cast<Recorder*>(self)->on(rbuf, channel);
  }
  void on(const lcm_recv_buf_t* rbuf, const std::string& channel) {
    try {  // nothing may unwind through LCM's C dispatch
      // The log's own receive time, as lcm-logger writes it.
      log->write(rbuf->recv_utime, channel, rbuf->data, static_cast<int32_t>(rbuf->data_size));
    } catch (const std::exception& e) {
      if (failures++ == 0) first_failure = e.what();
    }
  }
};

// Free space on the recording's file system: said at start, and warned about while recording when
// it falls below kLowBytes (again at each halving), with the time left at the current rate.
class FreeSpaceWatch {
 public:
  static constexpr double kLowBytes = 512e6;
  explicit FreeSpaceWatch(const std::string& path) {
    const std::filesystem::path p(path);
    dir_ = p.has_parent_path() ? p.parent_path().string() : ".";
    start_ = std::chrono::steady_clock::now();
  }
  void check(int64_t bytes_written, bool at_start) {
    const auto now = std::chrono::steady_clock::now();
    if (!at_start && now - last_ < std::chrono::seconds(2)) return;
    last_ = now;
    struct statvfs st {};
    if (::statvfs(dir_.c_str(), &st) != 0) return;  // a device or pipe: nothing to measure
    const double free_bytes = static_cast<double>(st.f_bavail) * static_cast<double>(st.f_frsize);
    if (at_start) {
      std::cerr << "[record] " << free_bytes / 1e6 << " MB free on the file system of '" << dir_ << "'"
                << (free_bytes < kLowBytes ? ": LOW, the recording may stop when it is full" : "") << std::endl;
      warn_below_ = free_bytes < kLowBytes ? free_bytes / 2 : kLowBytes;
      return;
    }
    if (free_bytes >= warn_below_) return;
    const double elapsed_s = std::chrono::duration<double>(now - start_).count();
    const double rate = elapsed_s > 0 ? bytes_written / elapsed_s : 0.0;
    std::cerr << "[record] warning: " << free_bytes / 1e6 << " MB free on '" << dir_ << "'";
    if (rate > 0) std::cerr << ", about " << static_cast<int64_t>(free_bytes / rate) << " s of recording left";
    std::cerr << std::endl;
    warn_below_ = free_bytes / 2;
  }

 private:
  std::string dir_;
  std::chrono::steady_clock::time_point start_, last_{};
  double warn_below_ = kLowBytes;
};

// Records until a stop signal, a failed LCM receive (returns true) or the first write failure
// (said at once, not only at the stop; ending lets a launcher see the recorder die and apply its
// policy instead of running on unrecorded).
bool recordUntilStopped(lcm::LCM& bus, omnislam::lcmio::LogWriter& log, Recorder& rec, double flush_interval_s,
                        FreeSpaceWatch& space) {
  // Wall time, not the messages' utime: this bounds what a crash of this process loses.
  const auto flush_every = std::chrono::duration<double>(flush_interval_s);
  auto last_flush = std::chrono::steady_clock::now();
  while (!omnislam::lcmio::stopRequested()) {
    if (bus.handleTimeout(100) < 0 && !omnislam::lcmio::stopRequested())
      return true;  // LCM cannot receive any more: stop rather than record nothing
    if (flush_interval_s > 0 && std::chrono::steady_clock::now() - last_flush >= flush_every) {
      last_flush = std::chrono::steady_clock::now();
      try {
        log.flushBuffered();
      } catch (const std::exception& e) {
        if (rec.failures++ == 0) rec.first_failure = e.what();
      }
    }
    space.check(log.bytes(), false);
    if (rec.failures > 0) {  // a failed write leaves the file torn there: nothing after it could be read
      std::cerr << "[record] WRITE FAILED, recording stopped: " << rec.first_failure << "; " << log.events()
                << " events (" << log.bytes() / 1e6 << " MB) are in the file" << std::endl;
      return false;
    }
  }
  return false;
}

struct Drain {
  int64_t messages = 0;
  bool cut = false;  ///< the bus was still busy when the drain ended
};

// What has already arrived, taken before the file is closed. Bounded: on a bus that stays busy it
// never ran dry, so the recorder ignored SIGINT and SIGTERM until the traffic stopped and the
// launcher's SIGKILL then lost the buffer and the report. It ends after kDrainS, or at once on a
// second SIGINT / SIGTERM.
Drain drainBus(lcm::LCM& bus) {
  constexpr double kDrainS = 0.5;
  const auto drain_end = std::chrono::steady_clock::now() + std::chrono::duration<double>(kDrainS);
  const int signals_at_stop = omnislam::lcmio::stopSignalCount();
  Drain d;
  while (bus.handleTimeout(0) > 0) {
    ++d.messages;
    if (std::chrono::steady_clock::now() >= drain_end ||
        (signals_at_stop > 0 && omnislam::lcmio::stopSignalCount() > signals_at_stop)) {
      d.cut = true;
      break;
    }
  }
  return d;
}

// The last line: events and bytes in the file; after a failure, the events lost with the write
// buffer and the failures (the messages refused after it are write failures).
void reportEnd(const omnislam::lcmio::LogWriter& log, const Recorder& rec, bool bus_failed, const Drain& drain) {
  std::cerr << "[record] " << log.events() << " events" << (rec.failures ? " in the file" : "") << ", "
            << log.bytes() / 1e6 << " MB"
            << (rec.failures
                    ? ", " + std::to_string(log.lost()) + " events lost with the write buffer, " +
                          std::to_string(rec.failures) + " WRITE FAILURES (the first: " + rec.first_failure + ")"
                    : "")
            << (bus_failed ? "; stopped: LCM failed to receive" : "")
            << (drain.cut ? "; the bus was still busy at the stop: the drain ended after " +
                                std::to_string(drain.messages) + " messages, the rest is not recorded"
                          : "")
            << std::endl;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{
      "omnislam-record: records an LCM bus into a log file (a flood can overflow UDP buffers: docs/user/lcm.md)"};
  std::string url, path, channels = ".*";
  int queue = 20000;
  double flush_interval_s = 0.5;
  cli.add_option("-f,--file", path, "output log file (overwritten)")->required();
  cli.add_option("--url", url, "LCM URL (default: $LCM_DEFAULT_URL)");
  cli.add_option("-c,--channels", channels, "channel regex (anchored, as in LCM)");
  cli.add_option("--queue", queue, "messages queued before LCM drops")->check(CLI::Range(30, 10'000'000));
  cli.add_option("--flush-interval-s", flush_interval_s,
                 "wall seconds between writes of the recorded messages to the file, bounding what a "
                 "SIGKILL or crash loses (0: only when the 32 KiB buffer is full)")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
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
    std::optional<omnislam::lcmio::LogWriter> opened;
    try {
      opened.emplace(path);
    } catch (const std::exception& e) {
      throw std::invalid_argument(std::string("--file: ") + e.what());
    }
    omnislam::lcmio::LogWriter& log = *opened;
    omnislam::lcmio::installStopHandlers();
    rec.log = &log;
    std::cerr << "[record] recording '" << channels << "' into " << path << std::endl;
    FreeSpaceWatch space(path);
    space.check(log.bytes(), true);
    const bool bus_failed = recordUntilStopped(bus, log, rec, flush_interval_s, space);
    const Drain drain = drainBus(bus);
    // Flush, sync and close the file: the writer writes its last buffer only now, so a full disk
    // shows here or not at all.
    try {
      log.commit();
    } catch (const std::exception& e) {
      if (rec.failures++ == 0) rec.first_failure = e.what();
    }
    reportEnd(log, rec, bus_failed, drain);
    return rec.failures || bus_failed ? omnislam::app::kFailure : omnislam::app::kOk;
  });
}
