// Frame <-> odometry pairing rules: see pairing.h and docs/user/slam-process.md.
#include "omnislam/runtime/pairing.h"

#include <algorithm>
#include <cmath>

#include "omnislam/runtime/pairing_options_table.h"

namespace omnislam::runtime {

namespace {
std::string us(int64_t v) { return std::to_string(v); }
}  // namespace

std::string PairingOptions::validate() const {
  const std::string ranges = options::checkRanges(*this, pairingFields());  // pairing_options_table.h
  if (!ranges.empty()) return ranges;
  if (odometry_buffer_us < max_wait_us)
    return "odometry_buffer_us must be >= max_wait_us (" + us(max_wait_us) + "), got " + us(odometry_buffer_us);
  return "";
}

UtimeOrderOptions PairingOptions::timeOrder() const {
  UtimeOrderOptions o;
  o.max_forward_jump_us = o.min_forward_jump_us = max_forward_jump_us;  // fixed: min >= max
  o.restart_back_jump_us = restart_jump_us;
  o.restart_confirm_messages = restart_confirm_messages;
  return o;
}

// ---- OdometryBuffer -------------------------------------------------------------------------

bool OdometryBuffer::add(int64_t utime, const Pose2& pose_O) {
  if (!samples_.empty() && utime <= samples_.back().first) return false;
  samples_.emplace_back(utime, pose_O);
  const int64_t limit = utime - keep_us_;
  // Keep the newest sample at or before the limit so that utimes down to the limit stay bracketed.
  while (samples_.size() > 2 && samples_[1].first <= limit) samples_.pop_front();
  return true;
}

OdometryBuffer::Lookup OdometryBuffer::at(int64_t utime, int64_t max_gap_us) const {
  Lookup r;
  if (samples_.empty()) return r;
  if (utime < samples_.front().first) {
    r.status = Status::kBeforeBuffer;
    return r;
  }
  if (utime > samples_.back().first) {
    r.status = Status::kAfterBuffer;
    return r;
  }
  // First sample with utime >= the query.
  const auto it = std::lower_bound(samples_.begin(), samples_.end(), utime,
                                   [](const std::pair<int64_t, Pose2>& s, int64_t t) { return s.first < t; });
  if (it->first == utime) {
    r.status = Status::kOk;
    r.pose_O = it->second;
    return r;
  }
  const auto& b = *it;
  const auto& a = *(it - 1);
  r.gap_us = b.first - a.first;
  if (r.gap_us > max_gap_us) {
    r.status = Status::kGapTooLarge;
    return r;
  }
  r.status = Status::kOk;
  r.pose_O = interpolate(a.second, b.second, static_cast<double>(utime - a.first) / static_cast<double>(r.gap_us));
  return r;
}

// ---- Pairer ---------------------------------------------------------------------------------

Pairer::Pairer(const PairingOptions& options)
    : opt_(options), order_opt_(options.timeOrder()), odom_(options.odometry_buffer_us) {}

InputResult Pairer::checkOrder(StreamState& self, int64_t utime) {
  InputResult r;
  if (self.awaiting_restart) {
    // The other stream restarted: this stream's messages from before the restart are stale until
    // it comes back to the new epoch's time.
    if (utime > epoch_.last() + opt_.restart_jump_us) {
      r.verdict = Verdict::kStaleAfterRestart;
      r.reason = "utime " + us(utime) + " is from before the restart (new epoch at " + us(epoch_.last()) + ")";
      ++stats_.stale_after_restart;
      return r;
    }
    self.awaiting_restart = false;
    self.order.forget();
  } else if (const TimeStep step = self.order.classify(utime, order_opt_);
             step == TimeStep::kDuplicate || step == TimeStep::kOutOfOrder || step == TimeStep::kJumpBack) {
    // Any step back is refused here; add() has already held those far enough back to be a restart.
    if (step == TimeStep::kDuplicate) {
      r.verdict = Verdict::kDuplicate;
      r.reason = "utime " + us(utime) + " repeated (duplicate)";
      ++stats_.duplicates;
    } else {
      r.verdict = Verdict::kOutOfOrder;
      r.reason = "utime " + us(utime) + " before previous " + us(self.order.last()) + " (out of order)";
      ++stats_.out_of_order;
    }
    return r;
  }
  self.order.take(utime);
  if (epoch_.empty() || utime > epoch_.last()) epoch_.take(utime);
  return r;
}

void Pairer::restart(int64_t utime, std::vector<PairEvent>& out) {
  ++stats_.restarts;
  while (!pending_.empty()) drop(out, "restart (utime jumped back)", stats_.dropped_restart);
  odom_.clear();
  T_OfromIn_ = Pose2{};
  have_last_odom_ = false;
  // A stream that has messages among the held ones starts afresh with them; the other one waits
  // until it comes back to the new epoch's time (its old-epoch messages are stale).
  bool held_frame = false, held_odom = false;
  for (const Input& h : held_) (h.is_frame ? held_frame : held_odom) = true;
  for (auto [st, held] : {std::pair{&frame_state_, held_frame}, std::pair{&odom_state_, held_odom}}) {
    st->awaiting_restart = !held && !st->order.empty();
    st->order.forget();
  }
  epoch_.forget();
  epoch_.take(utime);
  have_newest_frame_ = false;
  PairEvent ev;
  ev.kind = PairEvent::Kind::kReset;
  ev.reason = "restart at utime " + us(utime);
  out.push_back(std::move(ev));
}

void Pairer::refuseHeld(InputResult& r) {
  for (const Input& h : held_) {
    if (held_ahead_) {
      ++stats_.stray_ahead;
      r.refused_held.emplace_back(h.is_frame,
                                  "utime " + us(h.utime) + " jumped ahead and the stream went on (a stray stamp)");
    } else {
      ++stats_.out_of_order;
      r.refused_held.emplace_back(h.is_frame,
                                  "utime " + us(h.utime) + " jumped back and no restart followed (out of order)");
    }
  }
  held_.clear();
  held_ahead_ = false;
}

InputResult Pairer::addOdometry(int64_t utime, const Pose2& pose_O, std::vector<PairEvent>& out) {
  ++stats_.odometry_in;
  Input in;
  in.utime = utime;
  in.pose_O = pose_O;
  return add(std::move(in), out);
}

InputResult Pairer::addFrame(Frame frame, std::vector<PairEvent>& out) {
  ++stats_.frames_in;
  Input in;
  in.is_frame = true;
  in.utime = frame.utime;
  in.frame = std::move(frame);
  return add(std::move(in), out);
}

InputResult Pairer::add(Input in, std::vector<PairEvent>& out) {
  StreamState& self = in.is_frame ? frame_state_ : odom_state_;
  // Back: from this stream's last utime; ahead: from the newest utime of either stream.
  const bool jumped_back = !self.awaiting_restart && self.order.classify(in.utime, order_opt_) == TimeStep::kJumpBack;
  const bool jumped_ahead = !self.awaiting_restart && epoch_.classify(in.utime, order_opt_) == TimeStep::kJumpAhead;
  if (jumped_ahead) return holdAhead(std::move(in), out);
  if (jumped_back) {
    InputResult pre;
    if (held_ahead_) refuseHeld(pre);  // a jump ahead then one back: the first was a stray
    const std::string why = "utime jumped back from " + us(self.order.last()) + " to " + us(in.utime);
    held_.push_back(std::move(in));
    if (!heldConfirmed()) {
      InputResult r;
      r.verdict = Verdict::kDeferred;
      r.reason = why + ": held until a restart is confirmed";
      r.held = static_cast<int>(held_.size());
      r.refused_held = std::move(pre.refused_held);
      return r;
    }
    // Confirmed: a new epoch starts with the held messages, in their order.
    restart(held_.front().utime, out);
    InputResult r;
    r.restart = true;
    r.reason = why + ": restart";
    r.refused_held = std::move(pre.refused_held);
    applyHeld(r, out);
    return r;
  }
  InputResult pre;
  if (held_ahead_ && heldAheadCaughtUp(&in)) {
    // The stream went on after the held messages (the other stream had lagged behind): they were
    // no strays but a gap, and are taken before this one.
    ++stats_.forward_jumps;
    applyHeld(pre, out);
  } else if (!held_.empty() && held_.front().is_frame == in.is_frame) {
    refuseHeld(pre);  // the stream of the held messages went on as before: they were strays
  }
  InputResult r = apply(std::move(in), out);
  r.refused_held = std::move(pre.refused_held);
  if (held_ahead_ && heldAheadCaughtUp(nullptr)) {
    ++stats_.forward_jumps;  // the other stream caught up with them
    applyHeld(r, out);
  }
  return r;
}

bool Pairer::heldAheadCaughtUp(const Input* in) const {
  if (held_.empty()) return false;
  int64_t newest_same = -1, newest = held_.front().utime;
  for (const Input& h : held_) {
    newest = std::max(newest, h.utime);
    if (in && h.is_frame == in->is_frame) newest_same = std::max(newest_same, h.utime);
  }
  if (in) return newest_same >= 0 && in->utime > newest_same;
  return epoch_.classify(newest, order_opt_) != TimeStep::kJumpAhead;
}

InputResult Pairer::holdAhead(Input in, std::vector<PairEvent>& out) {
  InputResult pre;
  // Held messages of a step back, or of a jump ahead that this one does not continue, are refuted.
  // It continues them when it is after the last held message of its own stream (if any) and within
  // max_forward_jump_us of the newest held one: the two streams interleave, so a message may
  // come slightly before the other stream's last held one.
  bool continues = held_ahead_ && !held_.empty();
  if (continues) {
    int64_t newest = held_.front().utime;
    for (const Input& h : held_) {
      newest = std::max(newest, h.utime);
      if (h.is_frame == in.is_frame && in.utime <= h.utime) {
        // A duplicate or a late message among the held ones (two features processes in a swap's
        // overlap): refused as on a stream that was not held; it refutes nothing.
        InputResult r;
        r.verdict = in.utime == h.utime ? Verdict::kDuplicate : Verdict::kOutOfOrder;
        r.reason = "utime " + us(in.utime) +
                   (in.utime == h.utime ? " repeated (duplicate)" : " before a held message (out of order)");
        ++(in.utime == h.utime ? stats_.duplicates : stats_.out_of_order);
        return r;
      }
    }
    if (in.utime - newest > opt_.max_forward_jump_us || newest - in.utime > opt_.max_forward_jump_us) continues = false;
  }
  if (!held_.empty() && !continues) refuseHeld(pre);
  const std::string why = "utime " + us(in.utime) + " jumps ahead of the newest input " + us(epoch_.last()) +
                          " by more than " + us(opt_.max_forward_jump_us) + " us";
  held_ahead_ = true;
  held_.push_back(std::move(in));
  if (!heldConfirmed()) {
    InputResult r;
    r.verdict = Verdict::kDeferred;
    r.reason = why + ": held until the next messages confirm it";
    r.held = static_cast<int>(held_.size());
    r.refused_held = std::move(pre.refused_held);
    return r;
  }
  // Confirmed: the held messages are taken in their order, as after a restart but in the same epoch.
  ++stats_.forward_jumps;
  InputResult r;
  r.reason = why + ": confirmed, taken";
  r.refused_held = std::move(pre.refused_held);
  applyHeld(r, out);
  return r;
}

bool Pairer::heldConfirmed() const {
  if (static_cast<int>(held_.size()) < opt_.restart_confirm_messages) return false;
  bool held_frame = false, held_odom = false;
  int64_t first = held_.front().utime, last = first;
  for (const Input& h : held_) {
    (h.is_frame ? held_frame : held_odom) = true;
    first = std::min(first, h.utime);
    last = std::max(last, h.utime);
  }
  if (held_frame && held_odom) return true;  // both streams made the same jump
  // Only one stream jumped. While the other goes on at the old time, the held messages may be
  // strays (two consecutive frames with a bad stamp must not reset the filter): wait for the other
  // stream to jump too, or for the held stream to refute them by going on as before. The other
  // stream cannot confirm when it has said nothing in this epoch, and it may have gone silent: the
  // wait ends after max_wait_us of the held stream's own time or kMaxHeldMessages messages.
  const StreamState& other = held_frame ? odom_state_ : frame_state_;
  if (other.order.empty() || other.awaiting_restart) return true;
  return last - first >= opt_.max_wait_us || static_cast<int>(held_.size()) >= kMaxHeldMessages;
}

void Pairer::applyHeld(InputResult& r, std::vector<PairEvent>& out) {
  std::vector<Input> held = std::move(held_);
  held_.clear();
  held_ahead_ = false;
  for (Input& h : held) {
    const bool is_frame = h.is_frame;
    InputResult hr = apply(std::move(h), out);
    if (!hr.accepted()) r.refused_held.emplace_back(is_frame, hr.reason);
  }
}

InputResult Pairer::apply(Input in, std::vector<PairEvent>& out) {
  StreamState& self = in.is_frame ? frame_state_ : odom_state_;
  InputResult r = checkOrder(self, in.utime);
  if (!r.accepted()) return r;
  if (in.is_frame) {
    newest_frame_utime_ = have_newest_frame_ ? std::max(newest_frame_utime_, in.utime) : in.utime;
    have_newest_frame_ = true;
    pending_.push_back(std::move(in.frame));
  } else {
    if (have_last_odom_) {
      // A jump of the cumulative pose (odometry restarted in a new frame): re-base the stream so
      // that the new pose continues from the last one, assuming no motion over this interval.
      const Pose2 d = last_odom_in_.between(in.pose_O);
      const double dt_s = static_cast<double>(in.utime - last_odom_utime_) * 1e-6;
      if (std::hypot(d.x_m, d.y_m) > opt_.max_odometry_speed_mps * dt_s ||
          std::abs(d.theta_rad) > opt_.max_odometry_yaw_rate_radps * dt_s) {
        ++stats_.odometry_jumps;
        r.reason = "odometry pose jumped by " + std::to_string(std::hypot(d.x_m, d.y_m)) + " m, " +
                   std::to_string(d.theta_rad) + " rad in " + std::to_string(dt_s) + " s: re-based";
        T_OfromIn_ = T_OfromIn_.compose(last_odom_in_).compose(in.pose_O.inverse());
      }
    }
    have_last_odom_ = true;
    last_odom_utime_ = in.utime;
    last_odom_in_ = in.pose_O;
    const Pose2 pose_O = T_OfromIn_.compose(in.pose_O);
    if (!odom_.add(in.utime, pose_O)) {  // cannot happen: checkOrder keeps utimes increasing
      odom_.clear();
      odom_.add(in.utime, pose_O);
    }
  }
  decide(out, false);
  return r;
}

InputResult Pairer::finish(std::vector<PairEvent>& out) {
  InputResult r;
  refuseHeld(r);
  decide(out, true);
  return r;
}

void Pairer::drop(std::vector<PairEvent>& out, std::string reason, int64_t& counter) {
  PairEvent ev;
  ev.kind = PairEvent::Kind::kDropped;
  ev.frame = std::move(pending_.front());
  pending_.pop_front();
  ev.reason = "frame seq " + us(ev.frame.seq) + " utime " + us(ev.frame.utime) + " dropped: " + reason;
  ++counter;
  out.push_back(std::move(ev));
}

void Pairer::decide(std::vector<PairEvent>& out, bool at_end) {
  while (!pending_.empty()) {
    const Frame& f = pending_.front();
    const OdometryBuffer::Lookup L = odom_.at(f.utime, opt_.max_odometry_gap_us);
    switch (L.status) {
      case OdometryBuffer::Status::kOk: {
        PairEvent ev;
        ev.kind = PairEvent::Kind::kPaired;
        ev.frame = std::move(pending_.front());
        ev.odom_O = L.pose_O;
        pending_.pop_front();
        ++stats_.frames_paired;
        out.push_back(std::move(ev));
        continue;
      }
      case OdometryBuffer::Status::kGapTooLarge:
        drop(out,
             "odometry gap of " + us(L.gap_us) + " us around it (max_odometry_gap_us " + us(opt_.max_odometry_gap_us) +
                 ")",
             stats_.dropped_odometry_gap);
        continue;
      case OdometryBuffer::Status::kBeforeBuffer:
        drop(out, "older than the odometry buffer (from " + us(odom_.oldestUtime()) + ")", stats_.dropped_too_old);
        continue;
      case OdometryBuffer::Status::kEmpty:
      case OdometryBuffer::Status::kAfterBuffer: {
        const bool waited_too_long = newest_frame_utime_ - f.utime > opt_.max_wait_us;
        const bool too_many = static_cast<int>(pending_.size()) > opt_.max_pending_frames;
        if (at_end) {
          drop(out, "no odometry up to it at the end of the input", stats_.dropped_no_odometry);
        } else if (waited_too_long || too_many) {
          drop(out,
               std::string("no odometry up to it within ") +
                   (waited_too_long ? "max_wait_us " + us(opt_.max_wait_us)
                                    : "max_pending_frames " + std::to_string(opt_.max_pending_frames)),
               stats_.dropped_no_odometry);
        } else {
          return;  // wait for odometry
        }
        continue;
      }
    }
  }
}

}  // namespace omnislam::runtime
