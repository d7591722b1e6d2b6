// Bus connection with checked inputs and PROCESS_STATUS: see node.h.
#include "omnislam/lcmio/node.h"

#include <unistd.h>

#include <algorithm>
#include <iostream>
#include <stdexcept>

#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/sequence.h"
#include "omnislam/lcmio/signals.h"

namespace omnislam::lcmio {

Node::Node(std::string name, const std::string& url) : name_(std::move(name)), lcm_(url) {
  if (!lcm_.good()) throw std::runtime_error("cannot start LCM on '" + url + "' (check the URL and multicast routing)");
  installStopHandlers();
  next_status_ = std::chrono::steady_clock::now();
}

Node::~Node() = default;

void Node::dispatch(const lcm::ReceiveBuffer* rbuf, const std::string&, RawSubscription* sub) { sub->fn(rbuf); }

void Node::noteSequence(ChannelState& cs, const std::string& channel, int64_t seq, int64_t max_gap) {
  if (cs.have_seq) {
    const SequenceStep step = sequenceStep(cs.last_seq, seq, max_gap);
    counters_.sequence_gaps = saturatingAdd(counters_.sequence_gaps, step.missed);
    if (step.restart) {
      ++counters_.sequence_restarts;
      report(channel + ": sequence restarted at " + std::to_string(seq) + " after " + std::to_string(cs.last_seq) +
             (seq > cs.last_seq ? " (more than " + std::to_string(max_gap) + " ahead: not counted as missed messages)"
                                : ""));
    }
  }
  cs.have_seq = true;
  cs.last_seq = seq;
}

namespace {
/// One line: a reason may carry an exception's text, which can hold line breaks.
std::string oneLine(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}
}  // namespace

void Node::report(const std::string& line) {
  // One line per problem; after 20 lines only every 100th, so that a flood cannot drown the log.
  ++reports_;
  if (reports_ <= 20 || reports_ % 100 == 0)
    std::cerr << tag() << line << (reports_ > 20 ? " (" + std::to_string(reports_) + " problems so far)" : "")
              << std::endl;
}

bool Node::admitTime(ChannelState& cs, const std::string& channel, int64_t utime, const UtimeOrderOptions& order) {
  const int64_t restarts = cs.time.restarts(), strays = cs.time.strays();
  const auto why = cs.time.admit(utime, order);
  counters_.utime_strays += cs.time.strays() - strays;
  if (why) {
    reject(channel, *why);
    return false;
  }
  if (cs.time.restarts() != restarts) {
    ++counters_.utime_restarts;
    report(channel + ": " + cs.time.lastRestart());
  }
  return true;
}

bool Node::callHandler(ChannelState& cs, ChannelState before, const std::string& channel,
                       const std::function<void()>& call) {
  try {
    call();
    return true;
  } catch (const Refused& e) {
    cs = std::move(before);
    ++counters_.implausible;
    reject(channel, e.what());
  } catch (const std::exception& e) {
    cs = std::move(before);
    reject(channel, std::string("handling it failed: ") + e.what());
  } catch (...) {
    cs = std::move(before);
    reject(channel, "handling it failed: an unknown exception");
  }
  return false;
}

void Node::reject(const std::string& channel, const std::string& reason) {
  ++counters_.rejected_inputs;
  counters_.last_error = oneLine(channel + ": " + reason);
  report("rejected " + counters_.last_error);
}

void Node::error(const std::string& what) {
  counters_.last_error = oneLine(what);
  report("error: " + what);
}

void Node::publishStatus() {
  process_status_t st;
  st.utime = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
                 .count();
  st.seq = status_seq_++;
  st.name = name_;
  st.pid = static_cast<int32_t>(getpid());
  st.state = state_;
  st.messages_in = counters_.messages_in;
  st.messages_out = counters_.messages_out;
  st.decode_errors = counters_.decode_errors;
  st.rejected_inputs = counters_.rejected_inputs;
  st.sequence_gaps = counters_.sequence_gaps;
  st.last_error = counters_.last_error;
  st.detail = detail_;
  // The contract has no field for restarts of the inputs: they go with the detail, if any.
  if (counters_.sequence_restarts > 0 || counters_.utime_restarts > 0)
    st.detail += " [inputs restarted: " + std::to_string(counters_.sequence_restarts) + " seq, " +
                 std::to_string(counters_.utime_restarts) + " utime]";
  // Time jumps refused (strays, docs/user/lcm.md "Time faults") and implausible values, both also in
  // rejected_inputs: named here so that a reader of the status can tell them from other refusals.
  if (counters_.utime_strays > 0 || counters_.implausible > 0)
    st.detail += " [refused: " + std::to_string(counters_.utime_strays) + " stray utimes, " +
                 std::to_string(counters_.implausible) + " implausible]";
  if (lcm_.publish(channels::kProcessStatus, &st) != 0)
    error("publish on " + std::string(channels::kProcessStatus) + " failed");
  next_status_ = std::chrono::steady_clock::now() + std::chrono::seconds(1);
}

bool Node::handleFor(double timeout_s) {
  // Clamped before the cast: a NaN or huge timeout must not be undefined behaviour.
  const double clamped_ms = timeout_s > 0.0 ? std::min(timeout_s * 1000.0, 60'000.0) : 0.0;
  const int ms = static_cast<int>(clamped_ms);
  const int r = lcm_.handleTimeout(ms);
  if (std::chrono::steady_clock::now() >= next_status_) publishStatus();
  if (r < 0 && !stopRequested()) {
    error("LCM handle failed");
    return false;
  }
  return true;
}

void Node::spin(const std::function<bool()>& done, const std::function<void()>& tick) {
  if (state_ == process_status_t::STATE_STARTING) state_ = process_status_t::STATE_RUNNING;
  while (!stopRequested() && !(done && done())) {
    if (!handleFor(0.1)) break;
    if (tick) tick();
  }
}

}  // namespace omnislam::lcmio
