// Checkpoints of the SLAM process: the state of SlamDriver and Pairer to and from bytes, the file's
// envelope and the resume rules; see checkpoint.h and docs/user/slam-process.md.
#include "omnislam/runtime/checkpoint.h"

#include "omnislam/core/limits.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace omnislam::runtime {

namespace {

constexpr std::size_t kMaxItems = std::size_t{1} << 28;
constexpr std::uint32_t kPairerTag = 0x52494150u;  // "PAIR"
constexpr std::uint32_t kDriverTag = 0x56495244u;  // "DRIV"

void putPose(ByteWriter& w, const Pose2& p) {
  w.f64(p.x_m);
  w.f64(p.y_m);
  w.f64(p.theta_rad);
}
Pose2 getPose(ByteReader& r, const char* what) {
  Pose2 p;
  p.x_m = r.f64(what);
  p.y_m = r.f64(what);
  p.theta_rad = r.f64(what);
  return p;
}

void expectTag(ByteReader& r, std::uint32_t tag, const char* what) {
  if (r.u32(what) != tag) throw StateFormatError(std::string("no ") + what + " where one was expected (section tag)");
}

void putFrame(ByteWriter& w, const Frame& f) {
  w.i64(f.utime);
  w.i64(f.seq);
  w.i32(f.num_features);
  w.u64(f.z.size());
  for (const slam::BearingMeasurement& m : f.z) {
    w.f64(m.azimuth_rad);
    w.f64(m.elevation_rad);
    for (int i = 0; i < 4; ++i) w.f64(m.cov_rad2(i / 2, i % 2));
    for (int i = 0; i < 3; ++i) w.f64(m.p_CinR_m(i));
    w.u8(static_cast<std::uint8_t>(m.kind));
    w.boolean(m.descriptor.valid);
    for (float v : m.descriptor.rgb) w.f32(v);
  }
  w.u64(f.feature_index.size());
  for (int32_t i : f.feature_index) w.i32(i);
}

// A utime the state took from a message: within what lcmio::validate accepts, [0, 2^62] us, so that
// a corrupted checkpoint cannot overflow the arithmetic done on it (a buffer's horizon, a gap).
int64_t messageUtime(ByteReader& r, const char* what) {
  const int64_t t = r.i64(what);
  if (t < 0 || t > kMaxUtime)
    throw StateFormatError(std::string(what) + " " + std::to_string(t) + " is outside [0, 2^62] us");
  return t;
}

Frame getFrame(ByteReader& r) {
  Frame f;
  f.utime = messageUtime(r, "frame.utime");
  f.seq = r.i64("frame.seq");
  f.num_features = r.i32("frame.num_features");
  f.z.resize(r.count("frame measurements", kMaxItems, 99));
  for (slam::BearingMeasurement& m : f.z) {
    m.azimuth_rad = r.f64("measurement.azimuth_rad");
    m.elevation_rad = r.f64("measurement.elevation_rad");
    for (int i = 0; i < 4; ++i) m.cov_rad2(i / 2, i % 2) = r.f64("measurement.cov_rad2");
    for (int i = 0; i < 3; ++i) m.p_CinR_m(i) = r.f64("measurement.p_CinR_m");
    const std::uint8_t kind = r.u8("measurement.kind");
    if (kind > 1) throw StateFormatError("measurement kind " + std::to_string(kind) + " is not 0 or 1");
    m.kind = static_cast<slam::LandmarkKind>(kind);
    m.descriptor.valid = r.boolean("measurement.descriptor.valid");
    for (float& v : m.descriptor.rgb) v = r.f32("measurement.descriptor.rgb");
  }
  f.feature_index.resize(r.count("frame feature_index", kMaxItems, 4));
  for (int32_t& i : f.feature_index) i = r.i32("frame.feature_index");
  if (f.feature_index.size() != f.z.size()) throw StateFormatError("frame: feature_index is not one per measurement");
  return f;
}

template <class Ptr>
void putCounts(ByteWriter& w, const std::vector<Ptr>& v) {
  w.u64(v.size());
  for (const int64_t* x : v) w.i64(*x);
}
void getCounts(ByteReader& r, const std::vector<int64_t*>& v, const char* what) {
  const std::size_t n = r.count(what, kMaxItems, 8);
  if (n != v.size())
    throw StateFormatError(std::string(what) + ": " + std::to_string(n) + " counters, this program keeps " +
                           std::to_string(v.size()));
  for (int64_t* x : v) *x = r.i64(what);
}

template <class S>
auto pairingCounters(S& s) {  // S = PairingStats or const PairingStats
  return std::vector<decltype(&s.odometry_in)>{
      &s.odometry_in,     &s.frames_in,       &s.frames_paired, &s.dropped_no_odometry, &s.dropped_odometry_gap,
      &s.dropped_too_old, &s.dropped_restart, &s.duplicates,    &s.out_of_order,        &s.stale_after_restart,
      &s.restarts,        &s.forward_jumps,   &s.stray_ahead,   &s.odometry_jumps};
}

template <class S>
auto driverCounters(S& s) {  // S = DriverStats or const DriverStats; the pairing's are the pairer's
  return std::vector<decltype(&s.frames_processed)>{&s.frames_processed,
                                                    &s.features_in,
                                                    &s.features_skipped_kind,
                                                    &s.measurements_rejected,
                                                    &s.filter_resets,
                                                    &s.degenerate_weights,
                                                    &s.odometry_only_steps,
                                                    &s.dropped_behind_prediction,
                                                    &s.frames_too_large,
                                                    &s.implausible,
                                                    &s.reinit_last_estimate,
                                                    &s.health_uncertain,
                                                    &s.health_diverged,
                                                    &s.health_fallback,
                                                    &s.frames_between_keyframes,
                                                    &s.frames_localising,
                                                    &s.localisation_fixes,
                                                    &s.lost};
}

/// describe() without the lines of the map files (paths may differ between two starts of one run),
/// without filter.threads (it changes no result: a checkpoint resumes with any thread count, and
/// those written before the key existed still load) and without filter.association_linearised at
/// its default, false (the behaviour before the key existed: those checkpoints still load; true
/// stays in, as it changes the results).
std::string fingerprint(const SlamProcessOptions& o) {
  std::istringstream in(describe(o));
  std::string line, out;
  while (std::getline(in, line)) {
    if (line.rfind("map:", 0) == 0) continue;
    if (line.rfind("filter: ", 0) == 0) {
      const std::string key = " threads=";
      if (const std::size_t at = line.find(key); at != std::string::npos)
        line.erase(at, line.find_first_not_of("0123456789", at + key.size()) - at);
      const std::string exact = " association_linearised=false";
      if (const std::size_t at = line.find(exact); at != std::string::npos) line.erase(at, exact.size());
    }
    out += line + "\n";
  }
  return out;
}

std::string firstDifference(const std::string& a, const std::string& b) {
  std::istringstream ia(a), ib(b);
  std::string la, lb;
  while (true) {
    const bool ha = static_cast<bool>(std::getline(ia, la)), hb = static_cast<bool>(std::getline(ib, lb));
    if (!ha && !hb) return "";
    if (!ha || !hb || la != lb) return "'" + la + "' (checkpoint) vs '" + lb + "' (now)";
  }
}

/// A stream's time order as saved: its last utime, kept when it has none (after a restart) so that
/// a state saved again gives the same bytes. The usual interval is not saved: the pairing's
/// threshold is fixed (PairingOptions::timeOrder).
void restoreOrder(UtimeOrder& order, bool have_last, int64_t last_utime) {
  order.forget();
  order.take(last_utime);
  if (!have_last) order.forget();
}

}  // namespace

// ---- Pairer ---------------------------------------------------------------------------------

void Pairer::saveState(ByteWriter& w) const {
  w.u32(kPairerTag);
  w.u64(odom_.samples().size());
  for (const auto& [t, p] : odom_.samples()) {
    w.i64(t);
    putPose(w, p);
  }
  w.u64(pending_.size());
  for (const Frame& f : pending_) putFrame(w, f);
  w.u64(held_.size());
  for (const Input& in : held_) {
    w.boolean(in.is_frame);
    w.i64(in.utime);
    putPose(w, in.pose_O);
    putFrame(w, in.frame);
  }
  w.boolean(held_ahead_);
  putPose(w, T_OfromIn_);
  w.boolean(have_last_odom_);
  w.i64(last_odom_utime_);
  putPose(w, last_odom_in_);
  for (const StreamState* s : {&odom_state_, &frame_state_}) {
    w.boolean(!s->order.empty());
    w.i64(s->order.last());
    w.boolean(s->awaiting_restart);
  }
  w.boolean(!epoch_.empty());
  w.i64(epoch_.last());
  w.boolean(have_newest_frame_);
  w.i64(newest_frame_utime_);
  putCounts(w, pairingCounters(stats_));
}

void Pairer::loadState(ByteReader& r) {
  expectTag(r, kPairerTag, "pairing state");
  odom_.clear();
  const std::size_t n = r.count("odometry samples", kMaxItems, 32);
  for (std::size_t i = 0; i < n; ++i) {
    const int64_t t = messageUtime(r, "odometry sample utime");
    if (!odom_.add(t, getPose(r, "odometry sample pose")))
      throw StateFormatError("odometry samples not in increasing utime order");
  }
  pending_.clear();
  const std::size_t np = r.count("pending frames", kMaxItems, 36);
  for (std::size_t i = 0; i < np; ++i) pending_.push_back(getFrame(r));
  held_.resize(r.count("held messages", kMaxItems, 69));
  for (Input& in : held_) {
    in.is_frame = r.boolean("held.is_frame");
    in.utime = messageUtime(r, "held.utime");
    in.pose_O = getPose(r, "held.pose_O");
    in.frame = getFrame(r);
  }
  held_ahead_ = r.boolean("held_ahead");
  T_OfromIn_ = getPose(r, "T_OfromIn");
  have_last_odom_ = r.boolean("have_last_odom");
  last_odom_utime_ = messageUtime(r, "last_odom_utime");
  last_odom_in_ = getPose(r, "last_odom_in");
  for (StreamState* s : {&odom_state_, &frame_state_}) {
    const bool have_last = r.boolean("stream.have_last");
    restoreOrder(s->order, have_last, r.i64("stream.last_utime"));
    s->awaiting_restart = r.boolean("stream.awaiting_restart");
  }
  const bool have_epoch_newest = r.boolean("have_epoch_newest");
  restoreOrder(epoch_, have_epoch_newest, r.i64("epoch_newest_utime"));
  have_newest_frame_ = r.boolean("have_newest_frame");
  newest_frame_utime_ = messageUtime(r, "newest_frame_utime");
  getCounts(r, pairingCounters(stats_), "pairing counters");
}

// ---- SlamDriver -----------------------------------------------------------------------------

void SlamDriver::saveState(ByteWriter& w) const {
  w.u32(kDriverTag);
  pairer_.saveState(w);
  for (const slam::FastSlam* f : {filter_.get(), ended_filter_.get()}) {
    w.boolean(f != nullptr);
    if (f) f->saveState(w);
  }
  w.i64(ended_step_utime_);
  putPose(w, odom_prev_O_);
  for (int64_t v : {last_step_utime_, last_frame_utime_, odom_utime_at_last_frame_, epoch_, pose_seq_, map_seq_,
                    particles_seq_, associations_seq_, localisation_seq_})
    w.i64(v);
  putCounts(w, driverCounters(stats_));
  health_.saveState(w);
  w.i64(health_seq_);
  w.boolean(lost_.has_value());
  if (lost_) lost_->saveState(w);
}

void SlamDriver::loadState(ByteReader& r) {
  expectTag(r, kDriverTag, "driver state");
  // Read into a copy: a malformed state leaves this driver as it was.
  Pairer pairer = pairer_;
  pairer.loadState(r);
  std::unique_ptr<slam::FastSlam> filters[2];
  for (auto& f : filters)
    if (r.boolean("filter present")) f = std::make_unique<slam::FastSlam>(slam::FastSlam::loadState(opt_.filter, r));
  const int64_t ended_step_utime = messageUtime(r, "ended_step_utime");
  const Pose2 odom_prev = getPose(r, "odom_prev_O");
  int64_t v[9];
  for (int64_t& x : v) x = r.i64("driver counters");
  DriverStats stats = stats_;
  getCounts(r, driverCounters(stats), "driver counters");
  slam::HealthMonitor health = health_;
  health.loadState(r);
  const int64_t health_seq = r.i64("health seq");
  std::optional<slam::LostMonitor> lost = lost_;
  if (r.boolean("lost monitor present") != lost.has_value())
    throw StateFormatError("lost monitor present or not unlike this run's options and map");
  if (lost) lost->loadState(r);
  r.expectEnd("checkpoint");  // the driver's state ends a checkpoint
  pairer_ = std::move(pairer);
  filter_ = std::move(filters[0]);
  ended_filter_ = std::move(filters[1]);
  // The back end's keyframes are not in a checkpoint: it starts again at the restored estimate.
  if (filter_) startBackEnd(filter_->meanPose(), filter_->poseCovariance());
  ended_step_utime_ = ended_step_utime;
  odom_prev_O_ = odom_prev;
  last_step_utime_ = v[0];
  last_frame_utime_ = v[1];
  odom_utime_at_last_frame_ = v[2];
  epoch_ = v[3];
  pose_seq_ = v[4];
  map_seq_ = v[5];
  particles_seq_ = v[6];
  associations_seq_ = v[7];
  localisation_seq_ = v[8];
  lost_ = std::move(lost);
  restoreStart();
  stats_ = stats;
  health_ = std::move(health);
  health_seq_ = health_seq;
  // Derived, not stored: the estimate a restart of the inputs re-initialises from is the ended
  // filter's while no filter of the new epoch has started (apply(), kReset); the odometry
  // plausibility check takes its reference from the pairing at every message (checkOdometry), only
  // a jump waiting for confirmation at the checkpoint starts its count again.
  restart_from_.reset();
  if (!filter_ && ended_filter_ && !(lost_ && lost_->lost()))
    restart_from_ = Estimate{ended_filter_->meanPose(), ended_filter_->poseCovariance(), ended_filter_->bestMap()};
  odometry_check_.reset();
}

void SlamDriver::restoreStart() {
  // Start unknown: a restored filter tracks; without one the localising starts again (a checkpoint
  // is written only once a filter has stepped, and the localiser's hypotheses are not in it). Lost
  // (lost.policy relocalise): localising again in the kept map. Else the configured start.
  if (!start_) return;
  if (filter_) start_->resumeTracking();
  else if (lost_ && lost_->lost()) start_->restart(startMap());
  else if (opt_.start_source == SlamProcessOptions::StartSource::kUnknown) start_->restart();
  else start_->resumeTracking();
}

// ---- the file -------------------------------------------------------------------------------

std::string InputClock::admit(bool is_frame, int64_t utime) {
  const int s = is_frame ? 1 : 0;
  if (resumed_[s] >= 0) {
    if (utime > resumed_[s]) {
      resumed_[s] = -1;  // the stream has passed the checkpoint: the usual rules from here
    } else if (resumed_[s] - utime < restart_jump_us_) {
      ++already_processed_;
      return "utime " + std::to_string(utime) + " is not after the checkpoint's newest " +
             (is_frame ? "frame" : "odometry") + " utime " + std::to_string(resumed_[s]) + " (already processed)";
    }
  }
  newest_[s] = std::max(newest_[s], utime);
  return "";
}

void InputClock::resumeAfter(int64_t newest_odometry, int64_t newest_frame) {
  newest_[0] = resumed_[0] = newest_odometry;
  newest_[1] = resumed_[1] = newest_frame;
}

std::string CheckpointSummary::line() const {
  std::ostringstream o;
  o << "utime " << utime << ", " << frames << " frames processed, " << particles << " particles, " << landmarks
    << " landmarks";
  if (epoch > 0) o << " (after " << epoch << " input restart(s))";
  return o.str();
}

CheckpointSummary summarise(const SlamDriver& driver) {
  CheckpointSummary s;
  int64_t utime = 0;
  const slam::FastSlam* f = driver.filterToSave(&utime);
  s.utime = driver.filter() ? driver.lastStepUtime() : utime;
  s.frames = driver.stats().frames_processed;
  s.epoch = driver.stats().pairing.restarts;
  if (f) {
    s.particles = f->particles().size();
    s.landmarks = f->bestParticle().map.size();
  }
  return s;
}

std::vector<std::uint8_t> encodeCheckpoint(const SlamProcessOptions& options, const SlamDriver& driver,
                                           const InputClock& clock, const ReplayPosition& position) {
  ByteWriter w;
  w.str(fingerprint(options));
  w.i64(position.events);
  w.str(position.channel);
  w.i64(position.log_utime);
  w.i64(clock.newest(false));
  w.i64(clock.newest(true));
  driver.saveState(w);
  return sealState(kCheckpointMagic, kCheckpointVersion, w.buffer());
}

ReplayPosition decodeCheckpoint(const std::vector<std::uint8_t>& bytes, const SlamProcessOptions& options,
                                SlamDriver& driver, InputClock& clock) {
  const OpenedState st = openState(kCheckpointMagic, kCheckpointVersion, bytes.data(), bytes.size());
  ByteReader r(st.payload);
  const std::string saved = r.str("options", 1 << 20), now = fingerprint(options);
  if (saved != now) throw StateFormatError("written with other options: " + firstDifference(saved, now));
  ReplayPosition pos;
  pos.events = r.i64("replay position");
  pos.channel = r.str("replay channel", 4096);
  pos.log_utime = r.i64("replay log utime");
  const int64_t newest_odometry = r.i64("newest odometry utime"), newest_frame = r.i64("newest frame utime");
  driver.loadState(r);  // unchanged unless the whole state was read
  clock.resumeAfter(newest_odometry, newest_frame);
  return pos;
}

bool CheckpointSchedule::due(int64_t step_utime) {
  if (step_utime <= 0) return false;
  if (base_ < 0 || step_utime < base_) {  // the first step, or a restart stepped back
    base_ = step_utime;
    return false;
  }
  if (step_utime - base_ < interval_us_) return false;
  base_ = step_utime;
  return true;
}

}  // namespace omnislam::runtime
