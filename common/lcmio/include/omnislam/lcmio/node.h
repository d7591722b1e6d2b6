// A process's connection to the bus: typed subscriptions that decode, validate, check time order
// and sequence numbers, and count every failure; publishing with counters; PROCESS_STATUS about
// once per second; a loop that stops on SIGINT/SIGTERM. Bad input never reaches a handler.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "omnislam/lcmio/decode.h"
#include "omnislam/lcmio/sequence.h"
#include "omnislam/lcmio/utime_order.h"
#include "omnislam/lcmio/validate.h"
#include "omnislam/process_status_t.hpp"

namespace omnislam::lcmio {

/// Thrown by a subscription's handler to refuse its message (e.g. an implausible value): it is
/// counted in rejected_inputs and Counters::implausible and reported with `what()` as the reason,
/// and the channel's time order and sequence stay as they were (a refused message never changes
/// state). The handler must not have changed its own state before throwing.
struct Refused : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct InputOptions {
  /// Refuse a message whose utime is not after the previous accepted one on the channel
  /// (duplicates and time going backwards) or jumps far ahead of it; a new timeline is accepted
  /// after a few messages in a row continue it (utime_order.h, `time_order`).
  bool require_increasing_utime = true;
  UtimeOrderOptions time_order;
  /// Count gaps and restarts of seq (off for channels with several publishers, e.g. PROCESS_STATUS).
  bool track_sequence = true;
  /// A seq more than this ahead of the previous one counts as a restart, not as missed messages
  /// (sequence.h: a re-based counter or a corrupted field).
  int64_t max_sequence_gap = kMaxSequenceGap;
  /// LCM's per-subscription queue; arrivals beyond it are dropped by LCM (default 30 is small
  /// for bursts of images).
  int queue_capacity = 200;
  Limits limits;
};

struct Counters {
  int64_t messages_in = 0;
  int64_t messages_out = 0;
  int64_t decode_errors = 0;
  int64_t rejected_inputs = 0;
  int64_t sequence_gaps = 0;
  int64_t sequence_restarts = 0;
  int64_t utime_restarts = 0;  ///< new timelines accepted on the inputs (UtimeOrder)
  int64_t utime_strays = 0;    ///< inputs refused as a time jump that the next messages did not continue
  int64_t implausible = 0;     ///< inputs a handler refused by throwing Refused (plausibility)
  std::string last_error;
};

class Node {
 public:
  /// Connects to `url` ("" = LCM_DEFAULT_URL or LCM's default). Throws std::runtime_error if
  /// LCM cannot start. Installs the SIGINT/SIGTERM handlers.
  Node(std::string name, const std::string& url);
  ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  lcm::LCM& lcm() { return lcm_; }
  const std::string& name() const { return name_; }

  /// Subscribes `handler` to `channel` for messages of type Msg. Undecodable, invalid and
  /// out-of-order messages are counted, reported on one line and skipped. A handler that throws
  /// has its message counted and reported as refused ("handling it failed: ...") and the node goes
  /// on, so a handler must leave its state whole when it throws (check, then change).
  template <class Msg>
  void subscribe(const std::string& channel, std::function<void(const Msg&)> handler, InputOptions opt = {});

  /// Encodes and publishes; counts messages_out. Returns false (and records the error) on failure.
  template <class Msg>
  bool publish(const std::string& channel, const Msg& msg);

  /// Counts and reports a refused input (for checks done by the process itself).
  void reject(const std::string& channel, const std::string& reason);
  /// Records an error that is not about one input (e.g. a camera read failure).
  void error(const std::string& what);

  void setState(int8_t state) { state_ = state; }
  void setDetail(std::string detail) { detail_ = std::move(detail); }
  const Counters& counters() const { return counters_; }

  /// Handles messages for up to timeout_s (at most 60 s; NaN or <= 0: only what is there);
  /// publishes status when due. Returns false on an LCM error.
  bool handleFor(double timeout_s);
  /// Loops until a stop is requested or done() is true; calls tick() after every handle.
  void spin(const std::function<bool()>& done = {}, const std::function<void()>& tick = {});
  /// Publishes PROCESS_STATUS now.
  void publishStatus();

  /// Prefix for log lines: "[name] ".
  std::string tag() const { return "[" + name_ + "] "; }

 private:
  /// Time order and sequence of one subscription's stream (per subscription: two subscriptions
  /// to one channel each see every message).
  struct ChannelState {
    UtimeOrder time;
    bool have_seq = false;
    int64_t last_seq = 0;
  };
  struct RawSubscription {
    Node* node = nullptr;
    std::string channel;
    ChannelState state;
    std::function<void(const lcm::ReceiveBuffer*)> fn;
  };
  static void dispatch(const lcm::ReceiveBuffer* rbuf, const std::string& channel, RawSubscription* sub);
  void noteSequence(ChannelState& cs, const std::string& channel, int64_t seq, int64_t max_gap);
  /// The time-order check of a message's utime (its strays and restarts counted, a restart
  /// reported); false when it is refused (counted and reported).
  bool admitTime(ChannelState& cs, const std::string& channel, int64_t utime, const UtimeOrderOptions& order);
  /// Calls a subscription's handler. An exception must not unwind through LCM's C dispatch: LCM
  /// would stay "inside a handler" and abort on its next handle() (assert !lcm->in_handle). The
  /// message counts as refused, with the exception's text as the reason, the channel's state is put
  /// back to `before`, and the process goes on: false.
  bool callHandler(ChannelState& cs, ChannelState before, const std::string& channel,
                   const std::function<void()>& call);
  void report(const std::string& line);

  std::string name_;
  lcm::LCM lcm_;
  std::vector<std::unique_ptr<RawSubscription>> subs_;
  Counters counters_;
  int8_t state_ = process_status_t::STATE_STARTING;
  std::string detail_;
  int64_t status_seq_ = 0;
  int64_t reports_ = 0;
  std::chrono::steady_clock::time_point next_status_;
};

// ---- template implementation ---------------------------------------------------------------

template <class Msg>
void Node::subscribe(const std::string& channel, std::function<void(const Msg&)> handler, InputOptions opt) {
  auto sub = std::make_unique<RawSubscription>();
  sub->node = this;
  sub->channel = channel;
  sub->fn = [this, self = sub.get(), channel, handler = std::move(handler), opt](const lcm::ReceiveBuffer* rbuf) {
    ++counters_.messages_in;
    Msg msg;
    if (auto why = lcmio::decode(rbuf->data, rbuf->data_size, msg)) {
      ++counters_.decode_errors;
      counters_.last_error = channel + ": cannot decode " + std::to_string(rbuf->data_size) + " bytes as " +
                             Msg::getTypeName() + ": " + *why;
      report("decode error: " + counters_.last_error);
      return;
    }
    if (auto why = validate(msg, opt.limits)) {
      reject(channel, *why);
      return;
    }
    ChannelState& cs = self->state;
    // A message its handler refuses leaves the channel's time order and sequence as they were, like
    // any other refused message: the next one is judged against the last one handled, and the same
    // message sent again is not "a duplicate" of one that never took effect.
    ChannelState before = cs;
    if (opt.require_increasing_utime && !admitTime(cs, channel, msg.utime, opt.time_order)) return;
    if (!callHandler(cs, std::move(before), channel, [&] { handler(msg); })) return;
    // The seq of a message taken only: a refused copy of a real message (the same seq) is no
    // "sequence restart".
    if (opt.track_sequence) noteSequence(cs, channel, msg.seq, opt.max_sequence_gap);
  };
  lcm::Subscription* s = lcm_.subscribeFunction(channel, &Node::dispatch, sub.get());
  if (s == nullptr) throw std::runtime_error("cannot subscribe to " + channel);
  s->setQueueCapacity(opt.queue_capacity);
  subs_.push_back(std::move(sub));
}

template <class Msg>
bool Node::publish(const std::string& channel, const Msg& msg) {
  if (lcm_.publish(channel, &msg) != 0) {
    error("publish on " + channel + " failed");
    return false;
  }
  ++counters_.messages_out;
  return true;
}

}  // namespace omnislam::lcmio
