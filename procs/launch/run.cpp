// The run of a launch plan: the recorder first, then the processes; each process's end dealt with
// as the plan says (restarted with backoff, the run stopped, or left dead); a dead recorder
// stopped on or restarted into the next part file; the drain, the stop in order, the final report.
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <iomanip>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "launcher.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/signals.h"
#include "omnislam/process_status_t.hpp"
#include "status.h"
#include "supervisor.h"

namespace omnislam::launch {
namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

constexpr double kRecorderStartS = 20.0;  ///< longest wait for a recorder to say it records
constexpr double kLoggerGraceS = 5.0;     ///< the logger's least SIGINT-to-SIGKILL grace (Run::finish)
constexpr int kMessagesPerBatch = 1000;   ///< bus messages handled between two passes over the children

/// What the drain counts: messages but PROCESS_STATUS (published once a second by every process,
/// busy or idle), and when the last one came.
struct Activity {
  std::chrono::steady_clock::time_point last;
  int64_t messages = 0;
  void on(const lcm::ReceiveBuffer*, const std::string& channel) {
    if (channel == channels::kProcessStatus) return;
    last = std::chrono::steady_clock::now();
    ++messages;
  }
};

void ignore(const lcm::ReceiveBuffer*, const std::string&, void*) {}

/// The drain's bus listener, set up when the launcher starts, before anything publishes. LCM tests
/// the URL on its first subscription (it sends itself a message and waits for it): at the end of
/// the run, on a bus that stayed busy, that test lasted as long as the flood (holding the drain
/// past drain_s with no child looked after) or failed, and LCM then gave no subscription, which the
/// launcher used unchecked and crashed on. The channel subscribed to here is never published: LCM
/// queues nothing for the launcher until the drain subscribes to every channel.
/// The same instance publishes the launcher's status (publishing needs no subscription); nullptr
/// when LCM cannot use the URL at all. `listening` says whether the drain may listen on it.
std::unique_ptr<lcm::LCM> launcherBus(Supervisor& sup, const Plan& plan, bool& listening) {
  listening = false;
  auto bus = std::make_unique<lcm::LCM>(plan.lcm_url);
  if (!bus->good()) {
    sup.print("launch", "cannot use " + plan.lcm_url + ": no status published, and the drain waits the whole drain_s");
    return nullptr;
  }
  if (plan.drain_s <= 0 || plan.drain_quiet_s <= 0) return bus;
  listening = bus->subscribeFunction("OMNISLAM_LAUNCH_NOTHING", &ignore, static_cast<void*>(nullptr)) != nullptr;
  if (!listening)
    sup.print("launch", "cannot listen on " + plan.lcm_url + " for the drain: it will wait the whole drain_s");
  return bus;
}

/// The end of a run: the processes work through what they have queued (a loaded machine, a slow
/// filter) before they are stopped, since a process stopped by SIGINT leaves its queue unprocessed.
/// The bus is quiet once no message but PROCESS_STATUS has been seen for drain_quiet_s; drain_s
/// bounds the wait. The logger or a required process dying meanwhile ends it at once, reported
/// (the wait is for them; a busy bus held the failure unseen until drain_s), and marked reported,
/// so that the end of the run does not report them again. Nothing is restarted during the drain.
/// Returns false when the drain ended that way.
bool drainUntilQuiet(Supervisor& sup, const Plan& plan, lcm::LCM* bus, LaunchStatus& status) {
  using Clock = std::chrono::steady_clock;
  Activity activity;
  if (bus)
    if (lcm::Subscription* sub = bus->subscribe(".*", &Activity::on, &activity)) sub->setQueueCapacity(100000);
  const auto start = Clock::now();
  const auto until = start + std::chrono::duration<double>(plan.drain_s);
  activity.last = start;
  const auto quiet = std::chrono::duration<double>(plan.drain_quiet_s);
  bool busy = false;  // the last batch found the bus still busy: do not wait on the children
  while (Clock::now() < until && !lcmio::stopRequested()) {
    sup.pump(busy ? 0 : bus ? 20 : 50);
    status.tick();
    for (Child& c : sup.children) {
      if (!c.exited || c.reported) continue;
      if (!c.is_logger && (!failed(c.status) || !c.required)) continue;  // reported at the end, as before
      c.reported = true;
      sup.print("launch", (c.is_logger ? plan.log_tool + " died" : "process " + c.name + " died") +
                              " during the drain (" + describe(c.status) + "): stopping now" +
                              (c.is_logger ? ", the rest of the run is not recorded" : ""));
      return false;
    }
    if (!bus) continue;
    // What waits on the bus, in batches: a bus that never empties must not keep the launcher from
    // drain_s, a stop request and the children (it did, until the flood ended by itself).
    int handled = 0;
    while (handled < kMessagesPerBatch && Clock::now() < until && !lcmio::stopRequested() && bus->handleTimeout(0) > 0)
      ++handled;
    busy = handled == kMessagesPerBatch;
    if (Clock::now() - activity.last >= quiet) {
      const double s = std::chrono::duration<double>(Clock::now() - start).count();
      std::ostringstream o;
      o << std::fixed << std::setprecision(1) << "bus quiet after " << s << " s (" << activity.messages
        << " messages since the scenario ended)";
      sup.print("launch", o.str());
      return true;
    }
  }
  if (bus && !lcmio::stopRequested()) {
    std::ostringstream o;
    o << "drain_s (" << plan.drain_s << " s) reached before the bus was quiet for " << plan.drain_quiet_s << " s ("
      << activity.messages << " messages since the scenario ended): stopping anyway";
    sup.print("launch", o.str());
  }
  return true;
}

/// Seconds as the launcher prints them: "0.5", "2", "30".
std::string seconds(double s) {
  std::ostringstream o;
  o << s;
  return o.str();
}

class Run {
 public:
  Run(const Plan& plan, const std::string& bin_dir) : plan_(plan), bin_dir_(bin_dir), sup_(width(plan)) {}

  int exec() {
    sup_.print("launch", "run '" + plan_.name + "' on " + plan_.lcm_url);
    bus_ = launcherBus(sup_, plan_, listening_);
    status_ = std::make_unique<LaunchStatus>(bus_.get());
    status_->setState(process_status_t::STATE_STARTING);
    if (plan_.log_enabled && !startRecorder()) {
      sup_.print("launch", "done with errors");
      return 1;
    }
    startProcesses();
    status_->setState(process_status_t::STATE_RUNNING);
    while (reason_.empty()) superviseOnce();
    finish();
    return report();
  }

 private:
  static size_t width(const Plan& plan) {
    size_t w = 6;
    for (const auto& p : plan.processes) w = std::max(w, p.name.size());
    return w;
  }

  double nowS() const { return std::chrono::duration<double>(Clock::now() - t0_).count(); }

  Child& logger() { return sup_.children.front(); }  // startRecorder() puts it first

  /// The recorder, before anything publishes. False when it ended before it said it records.
  bool startRecorder() {
    const fs::path dir = fs::path(plan_.log_file).parent_path();
    if (!dir.empty()) fs::create_directories(dir);
    Child lg = spawn("logger", recorderArgv(plan_, plan_.log_file), plan_.lcm_url, bin_dir_);
    lg.is_logger = true;
    // omnislam-record prints this line once it has opened the file and subscribed; lcm-logger
    // prints it just before it opens the file and subscribes (and ends at once if it cannot open
    // it). Any other line (an error, LCM's warning) is not the start.
    lg.ready_line = plan_.log_tool == "lcm-logger" ? "Opening log file" : "[record] recording";
    RestartOptions ro;
    ro.mode = plan_.on_recorder_failure == RecorderFailure::kRestart ? RestartMode::kOnFailure : RestartMode::kNever;
    ro.delay_s = ro.delay_max_s = 0.0;  // at once: the gap is what is lost
    ro.limit = plan_.recorder_restart_limit;
    ro.window_s = plan_.recorder_restart_window_s;
    lg.restart = std::make_shared<RestartPolicy>(ro);
    sup_.children.push_back(lg);
    sup_.print("launch", "recording every channel into " + plan_.log_file + " (" + plan_.log_tool + "), pid " +
                             std::to_string(lg.pid));
    waitUntilRecording(Clock::now() +
                       std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kRecorderStartS)));
    // A recorder that has ended records nothing (it could not write the file): the run stops
    // before it starts. Its error line used to pass for the start, and the run went on unrecorded.
    if (logger().exited && !lcmio::stopRequested()) {
      sup_.print("launch", plan_.log_tool + " ended before it started recording (" + describe(logger().status) +
                               "): starting nothing");
      return false;
    }
    return true;
  }

  /// Waits (a loaded machine starts processes slowly) for the recorder's line, then a short margin.
  void waitUntilRecording(Clock::time_point deadline) {
    while (!logger().ready && !logger().exited && !lcmio::stopRequested() && Clock::now() < deadline) sup_.pump(20);
    if (!logger().ready && !logger().exited && !lcmio::stopRequested())
      sup_.print("launch", plan_.log_tool + " has not said it is recording after " + seconds(kRecorderStartS) + " s");
    if (!lcmio::stopRequested()) sup_.pumpFor(std::chrono::milliseconds(300));
    if (logger().ready) recordingInto(logPartFile(plan_.log_file, log_part_));
  }

  void recordingInto(const std::string& file) {
    log_files_.push_back(file);
    recording_ = true;
    updateDetail();
  }

  /// A stop while waiting for the logger starts nothing (the loop stops what runs).
  void startProcesses() {
    for (const auto& p : plan_.processes) {
      if (lcmio::stopRequested()) break;
      Child c = spawn(p.name, p.argv, plan_.lcm_url, bin_dir_);
      c.ends_run = p.ends_run;
      c.required = p.required;
      c.restart = std::make_shared<RestartPolicy>(p.restart);
      sup_.children.push_back(c);
      std::string cmd;
      for (const auto& a : p.argv) cmd += (cmd.empty() ? "" : " ") + a;
      sup_.print("launch", "started " + p.name + " (pid " + std::to_string(c.pid) + "): " + cmd);
    }
  }

  /// One pass: output, ends, due restarts, the recorder's state. Sets reason_ when the run ends.
  void superviseOnce() {
    sup_.pump(pumpTimeoutMs());
    status_->tick();
    if (lcmio::stopRequested()) {
      reason_ = "interrupted (signal " + std::to_string(lcmio::stopSignal()) + ")";
      return;
    }
    for (Child& c : sup_.children) {
      if (!c.exited || c.reported) continue;
      c.reported = true;
      if (c.is_logger) onRecorderExit(c);
      else onProcessExit(c);
      if (!reason_.empty()) return;
    }
    startDueRestarts();
    if (plan_.log_enabled && !recording_ && !logger().exited) checkRestartedRecorder();
    bool any_running = false;
    for (const auto& c : sup_.children) any_running = any_running || (!c.is_logger && (!c.exited || c.restart_pending));
    if (!any_running) reason_ = "every process has ended";
  }

  /// A restarted recorder counts as recording once it says so; one that has not said so within
  /// 20 s stops the run (as at the start).
  void checkRestartedRecorder() {
    if (logger().ready) {
      recordingInto(logPartFile(plan_.log_file, log_part_));
      std::ostringstream o;
      o << "recording again into " << log_files_.back() << ", " << std::fixed << std::setprecision(2)
        << nowS() - recorder_down_s_ << " s after the recorder's end was seen (what it had not yet written is lost "
        << "too: omnislam-logstat on every part shows exactly what)";
      say(o.str());
    } else if (nowS() - recorder_down_s_ > kRecorderStartS) {
      say(plan_.log_tool + " has not said it is recording " + seconds(kRecorderStartS) +
          " s after its restart: stopping the run now, without the drain");
      rc_ = 1;
      reason_ = "logger not recording";
      logger_died_ = true;
    }
  }

  /// Until the next restart is due, at most 100 ms.
  int pumpTimeoutMs() const {
    int ms = 100;
    for (const auto& c : sup_.children)
      if (c.restart_pending) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(c.restart_at - Clock::now()).count();
        ms = static_cast<int>(std::clamp<int64_t>(left, 0, ms));
      }
    return ms;
  }

  /// A launcher line that is also a supervision event on the status channel.
  void say(const std::string& line) {
    sup_.print("launch", line);
    status_->event(line);
  }

  void onProcessExit(Child& c) {
    const bool bad = failed(c.status);
    if (!bad && c.ends_run) {
      reason_ = c.name + " finished the scenario";
      return;
    }
    const std::string how =
        bad ? "process " + c.name + " died: " + describe(c.status) : c.name + " finished (exit code 0)";
    const RestartDecision d = c.restart->onExit(bad, c.ends_run, false, nowS());
    if (d.kind == RestartDecision::Kind::kRestart) {
      c.restart_pending = true;
      c.restart_at =
          Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(d.delay_s));
      say(how + "; restart " + std::to_string(d.number) + " of " + std::to_string(d.limit) + " (within " +
          seconds(c.restart->options().window_s) + " s) in " + seconds(d.delay_s) + " s");
      updateDetail();
      return;
    }
    if (d.kind == RestartDecision::Kind::kExhausted) {
      // After a normal exit (restart: always) it is left ended, as a normal exit without restarts is.
      say(how + "; restarts exhausted (" + std::to_string(d.limit) + " within " +
          seconds(c.restart->options().window_s) + " s)" +
          (!bad         ? ": left ended"
           : c.required ? ": stopping the run"
                        : ": not required, left dead"));
      if (bad && c.required) {
        rc_ = 1;
        reason_ = c.name + " died, its restarts exhausted";
      }
      return;
    }
    sup_.print("launch", how);
    if (bad && c.required) {
      rc_ = 1;
      reason_ = c.name + " died";
    }
  }

  /// The documented policy for a dead recorder (logger.on_failure): stop the run at once, without
  /// the drain, or start a new recorder into the next part file at once. Never "recording" when not.
  void onRecorderExit(Child& c) {
    recording_ = false;
    recorder_down_s_ = nowS();
    updateDetail();
    const RestartDecision d = c.restart->onExit(true, false, false, nowS());
    const std::string died = plan_.log_tool + " died (" + describe(c.status) + "): the run is not being recorded; ";
    if (d.kind == RestartDecision::Kind::kRestart) {
      ++log_part_;
      c.argv = recorderArgv(plan_, logPartFile(plan_.log_file, log_part_));
      say(died + "restarting it into " + logPartFile(plan_.log_file, log_part_) + " (restart " +
          std::to_string(d.number) + " of " + std::to_string(d.limit) + ")");
      if (respawn(c)) {
        sup_.print("launch", "restarted " + plan_.log_tool + " (pid " + std::to_string(c.pid) + ")");
        return;
      }
    } else {
      say(died + (d.kind == RestartDecision::Kind::kExhausted
                      ? "its restarts are exhausted (" + std::to_string(d.limit) + " within " +
                            seconds(plan_.recorder_restart_window_s) + " s): stopping the run now, without the drain"
                      : "stopping it now, without the drain"));
    }
    rc_ = 1;
    reason_ = "logger died";
    logger_died_ = true;
  }

  /// Starts `c` again; false (said) when it cannot be started.
  bool respawn(Child& c) {
    try {
      sup_.respawn(c, plan_.lcm_url, bin_dir_);
      return true;
    } catch (const std::exception& e) {
      say("cannot restart " + c.name + ": " + e.what());
      c.exited = c.reported = true;
      return false;
    }
  }

  void startDueRestarts() {
    for (Child& c : sup_.children) {
      if (!c.restart_pending || Clock::now() < c.restart_at) continue;
      c.restart_pending = false;
      if (!respawn(c)) {
        if (c.required) {
          rc_ = 1;
          reason_ = c.name + " could not be restarted";
        }
        continue;
      }
      sup_.print("launch", "restarted " + c.name + " (pid " + std::to_string(c.pid) + ")");
    }
  }

  /// The status detail: what is recorded, and the restarts so far.
  void updateDetail() {
    std::string d = !plan_.log_enabled ? "not recording (logger disabled)"
                    : recording_       ? "recording into " + (log_files_.empty() ? plan_.log_file : log_files_.back())
                                       : "NOT recording";
    std::string restarts;
    for (const auto& c : sup_.children)
      if (c.restart && c.restart->restarts() > 0)
        restarts += (restarts.empty() ? "" : ", ") + c.name + " " + std::to_string(c.restart->restarts());
    if (!restarts.empty()) d += "; restarts: " + restarts;
    status_->setDetail(d);
  }

  /// The drain, then the processes stopped, then the recorder.
  void finish() {
    sup_.print("launch", "stopping: " + reason_);
    for (Child& c : sup_.children)
      if (c.restart_pending) {
        c.restart_pending = false;
        sup_.print("launch", c.name + " is not restarted: the run is stopping");
      }
    status_->setState(process_status_t::STATE_STOPPING);
    // The drain lets the processes finish what they queued, for the recording: without a recorder
    // it would only let the run go on unrecorded (up to drain_s).
    if (!lcmio::stopRequested() && !logger_died_ && plan_.drain_s > 0 &&
        !drainUntilQuiet(sup_, plan_, listening_ ? bus_.get() : nullptr, *status_))
      rc_ = 1;
    sup_.stop(false, plan_.stop_grace_s);
    // The logger goes last, after a moment for the final messages (status, last frame) to land.
    status_->setState(rc_ == 0 ? process_status_t::STATE_FINISHED : process_status_t::STATE_ERROR);
    sup_.pumpFor(std::chrono::milliseconds(300));
    // Its grace is at least kLoggerGraceS: a recorder stopping on a busy bus records what has
    // arrived for up to 0.5 s, then writes and syncs the file, and a stop_grace_s below that (0.1 s
    // is accepted) killed it in the middle, losing the report and what it held. The wait ends as
    // soon as it has stopped, so the floor costs nothing when it stops at once.
    sup_.stop(true, std::max(plan_.stop_grace_s, kLoggerGraceS));
  }

  int report() {
    for (const Child& c : sup_.children) {
      const bool stopped_by_us = WIFSIGNALED(c.status) && WTERMSIG(c.status) == SIGINT;
      if (failed(c.status) && !stopped_by_us && !c.reported) {
        sup_.print("launch", "process " + c.name + " ended badly while stopping: " + describe(c.status));
        rc_ = 1;
      }
      if (c.group_killed) rc_ = 1;
    }
    // Only the files the recorder said it writes (one stopped while it started has nothing).
    for (const auto& f : log_files_)
      if (fs::exists(f)) sup_.print("launch", "log: " + f);
    if (log_files_.size() > 1)
      sup_.print("launch", "the recording is in " + std::to_string(log_files_.size()) +
                               " parts with gaps between them: omnislam-logstat PART1 PART2 ... shows what was lost");
    if (lcmio::stopRequested()) {
      // Everything was stopped in order and the recording closed, but the run did not end by
      // itself: 128 + signal (the shell's convention) lets a script tell it from a finished run.
      sup_.print("launch", rc_ == 0 ? "done (interrupted)" : "done with errors (interrupted)");
      return 128 + lcmio::stopSignal();
    }
    sup_.print("launch", rc_ == 0 ? "done" : "done with errors");
    return rc_;
  }

  const Plan& plan_;
  const std::string bin_dir_;
  Supervisor sup_;
  std::unique_ptr<lcm::LCM> bus_;
  bool listening_ = false;  ///< the drain may listen on bus_
  std::unique_ptr<LaunchStatus> status_;
  const Clock::time_point t0_ = Clock::now();
  int rc_ = 0;
  std::string reason_;
  bool logger_died_ = false;  ///< the run stops without the drain (docs/user/launch-file.md)
  bool recording_ = false;    ///< the recorder said it records and has not ended since
  int log_part_ = 1;
  std::vector<std::string> log_files_;  ///< the parts the recorder said it records into
  double recorder_down_s_ = 0.0;
};

}  // namespace

int runPlan(const Plan& plan, const std::string& bin_dir) {
  checkPrograms(plan, bin_dir);
  lcmio::installStopHandlers();
  return Run(plan, bin_dir).exec();
}

}  // namespace omnislam::launch
