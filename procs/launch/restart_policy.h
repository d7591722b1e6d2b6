// The launcher's restart rule for one process (docs/user/launch-file.md, "Restarts"): whether an exit is
// restarted, after which delay, and when the restarts are exhausted. Pure: no clock, no process;
// the caller gives the time of each exit in seconds on any monotonic clock.
//
// Backoff: the k-th restart within the last window_s seconds waits
//   delay_k = min(delay_s * 2^(k-1), delay_max_s),
// so a process that crashes in a loop is restarted less and less often, and one that has run for a
// whole window without failing is back at delay_s. Limit: when `limit` restarts already lie within
// the window, the next exit is not restarted (exhausted), as systemd's StartLimitBurst in
// StartLimitIntervalSec and procman's restart limit do.
#pragma once

#include <deque>
#include <string>

namespace omnislam::launch {

enum class RestartMode {
  kNever,      ///< never restarted (the launcher's behaviour before restarts existed)
  kOnFailure,  ///< restarted after an exit by a signal or with a non-zero code
  kAlways,     ///< also after a normal exit (not an ends_run process's: that ends the run)
};

/// "never" | "on_failure" | "always".
std::string toString(RestartMode mode);

struct RestartOptions {
  RestartMode mode = RestartMode::kNever;
  double delay_s = 0.5;       ///< delay before the first restart within a window
  double delay_max_s = 30.0;  ///< the doubling delay stops growing here (>= delay_s)
  int limit = 5;              ///< restarts allowed within window_s
  double window_s = 60.0;     ///< the sliding window of the limit and of the backoff
};

struct RestartDecision {
  enum class Kind {
    kNotWanted,  ///< the mode does not restart this exit, or the run is stopping
    kRestart,    ///< restart after delay_s
    kExhausted,  ///< wanted, but `limit` restarts already lie within the window
  };
  Kind kind = Kind::kNotWanted;
  int number = 0;        ///< kRestart: this restart is number `number` of `limit` within the window
  int limit = 0;         ///< the options' limit
  double delay_s = 0.0;  ///< kRestart: wait this long before starting it again
};

class RestartPolicy {
 public:
  explicit RestartPolicy(const RestartOptions& options = {}) : options_(options) {}

  /// The decision for an exit at now_s. `failed`: ended by a signal or with a non-zero exit code.
  /// `ends_run`: the process's normal exit ends the run. `run_stopping`: the run is being stopped
  /// (nothing is restarted then). A kRestart is counted in the window at now_s.
  RestartDecision onExit(bool failed, bool ends_run, bool run_stopping, double now_s);

  /// Restarts decided in total (not only within the window).
  int restarts() const { return total_; }
  const RestartOptions& options() const { return options_; }

 private:
  RestartOptions options_;
  std::deque<double> recent_s_;  ///< times of the restarts within the window, oldest first
  int total_ = 0;
};

}  // namespace omnislam::launch
