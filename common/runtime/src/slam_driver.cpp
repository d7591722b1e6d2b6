// The SLAM process's shared code path: see slam_driver.h and docs/user/slam-process.md.
#include "omnislam/runtime/slam_driver.h"

#include "omnislam/runtime/map_message.h"
#include "omnislam/runtime/thread_pool.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace omnislam::runtime {

std::optional<slam::BearingMeasurement> toMeasurement(const feature_t& f, const double camera_position_m[3],
                                                      const SlamProcessOptions& options) {
  slam::BearingMeasurement m;
  if (f.kind == feature_t::KIND_CEILING_LIGHT) {
    if (!options.use_ceiling_lights || !f.has_elevation) return std::nullopt;
    m.kind = slam::LandmarkKind::kPoint3D;
    m.elevation_rad = f.elevation_rad;
  } else if (f.kind == feature_t::KIND_VERTICAL_LINE) {
    if (!options.use_vertical_lines) return std::nullopt;
    m.kind = slam::LandmarkKind::kVerticalLine;
    m.elevation_rad = 0.0;
  } else {
    return std::nullopt;
  }
  m.azimuth_rad = f.azimuth_rad;
  if (m.kind == slam::LandmarkKind::kVerticalLine) {  // the neighbourhood colours (paper 002)
    bool any = false;
    for (int i = 0; i < 3; ++i) {
      m.descriptor.rgb[static_cast<std::size_t>(i)] = f.colour_a[i];
      m.descriptor.rgb[static_cast<std::size_t>(i + 3)] = f.colour_b[i];
      any = any || f.colour_a[i] != 0.0f || f.colour_b[i] != 0.0f;
    }
    m.descriptor.valid = any && std::isfinite(f.colour_a[0] + f.colour_a[1] + f.colour_a[2] + f.colour_b[0] +
                                              f.colour_b[1] + f.colour_b[2]);
  }
  m.cov_rad2 << f.covariance[0][0], f.covariance[0][1], f.covariance[1][0], f.covariance[1][1];
  const double floor = options.min_sigma_rad * options.min_sigma_rad;
  for (int i = 0; i < 2; ++i)
    if (m.cov_rad2(i, i) < floor) m.cov_rad2(i, i) = floor;
  m.p_CinR_m = Eigen::Vector3d(camera_position_m[0], camera_position_m[1], camera_position_m[2]);
  return m;
}

slam_trajectory_t trajectoryMessage(const BackEndReport& r, const Frame& frame, int64_t seq) {
  slam_trajectory_t m{};
  m.utime = frame.utime;
  m.seq = seq;
  m.input_seq = frame.seq;
  m.solved_at_utime = r.solved_at_utime;
  m.ok = r.ok;
  m.failure = r.ok ? "" : r.failure.substr(0, r.failure.find('\n'));
  m.num_landmarks = r.num_landmarks;
  m.num_bearings = r.num_bearings;
  m.num_removed = r.num_removed;
  m.iterations = r.iterations;
  m.final_cost = r.final_cost;
  m.loop_closure = r.loop_closure;
  m.num_keyframes = static_cast<int32_t>(r.keyframe_poses.size());
  for (std::size_t k = 0; k < r.keyframe_poses.size(); ++k) {
    m.keyframe_utime.push_back(r.keyframe_utimes[k]);
    m.x_m.push_back(r.keyframe_poses[k].x_m);
    m.y_m.push_back(r.keyframe_poses[k].y_m);
    m.theta_rad.push_back(r.keyframe_poses[k].theta_rad);
  }
  return m;
}

Frame toFrame(const features_t& msg, const SlamProcessOptions& options, int64_t* skipped) {
  Frame fr;
  fr.utime = msg.utime;
  fr.seq = msg.seq;
  fr.z.reserve(msg.features.size());
  fr.num_features = static_cast<int32_t>(msg.features.size());
  for (std::size_t i = 0; i < msg.features.size(); ++i) {
    const feature_t& f = msg.features[i];
    if (auto m = toMeasurement(f, msg.camera_position_m, options)) {
      fr.z.push_back(*m);
      fr.feature_index.push_back(static_cast<int32_t>(i));
    } else if (skipped) {
      ++*skipped;
    }
  }
  return fr;
}

SlamDriver::SlamDriver(const SlamProcessOptions& options, std::vector<slam::Landmark> prior_map)
    : opt_(options),
      pairer_(options.pairing),
      prior_map_(std::move(prior_map)),
      health_(options.health, options.filter.motion) {
  if (opt_.localisation_only) opt_.filter.update_map = false;
  const std::string err = opt_.validate();
  if (!err.empty()) throw std::invalid_argument("SLAM options: " + err);
  if (opt_.localisation_only && prior_map_.empty())
    throw std::invalid_argument("SLAM options: localisation only needs a non-empty prior map");
  if (opt_.start_source == SlamProcessOptions::StartSource::kUnknown) {
    if (prior_map_.empty())
      throw std::invalid_argument("SLAM options: start_pose.source unknown needs a non-empty loaded map");
    start_ = std::make_unique<GlobalStart>(opt_.localisation, opt_.filter, prior_map_);
  }
  if (opt_.lost.policy == slam::LostPolicy::kRelocalise && !prior_map_.empty()) {
    lost_.emplace(opt_.lost, opt_.localisation, opt_.filter.perception.detection_probability);
    if (opt_.filter.update_map) lost_->keepMap(prior_map_);
    if (!start_) {  // the configured start first; the localiser only once lost
      start_ = std::make_unique<GlobalStart>(opt_.localisation, opt_.filter, prior_map_);
      start_->resumeTracking();
    }
  }
}

const DriverStats& SlamDriver::stats() const {
  stats_.pairing = pairer_.stats();
  return stats_;
}

void SlamDriver::note(const InputResult& in, const char* channel, DriverResult& r) {
  for (const auto& [is_frame, why] : in.refused_held)
    r.refused.push_back({is_frame ? "OMNI_FEATURES" : "ODOMETRY", why});
  if (!in.accepted() && in.verdict != Verdict::kDeferred) {
    r.refused.push_back({channel, in.reason});
  } else if (!in.reason.empty() && !(in.verdict == Verdict::kDeferred && in.held > 1)) {
    // Held for a restart or a jump ahead (the first message of it: the others held while it waits
    // for the other stream say nothing new), a restart, a jump taken, an odometry jump re-based.
    r.notes.push_back(std::string(channel) + " " + in.reason);
  }
}

namespace {
std::string num(double v) {
  std::ostringstream o;
  o.precision(6);
  o << v;
  return o.str();
}

/// The pose and its covariance (x, y in metres, theta in radians) written into p.
void setPose(pose_t& p, const Pose2& pose_W, const Eigen::Matrix3d& cov) {
  p.x_m = pose_W.x_m;
  p.y_m = pose_W.y_m;
  p.theta_rad = pose_W.theta_rad;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) p.covariance[i][j] = cov(i, j);
}

}  // namespace

std::optional<std::string> SlamDriver::checkOdometry(const odometry_t& msg) {
  const PlausibilityOptions& b = opt_.plausibility;
  const std::string at = "seq " + std::to_string(msg.seq) + " ";
  if (!(std::abs(msg.theta_rad) <= b.max_odometry_angle_rad))
    return at + "theta " + num(msg.theta_rad) + " rad beyond plausibility.max_odometry_angle_rad " +
           num(b.max_odometry_angle_rad) + " (a corrupted field?)";
  // Judged from the last odometry the pairing took (the reference a refused one never becomes);
  // a jump confirmed by jump_confirm_messages in a row passes, and the pairing re-bases it.
  int64_t ref_utime = 0;
  Pose2 ref;
  if (pairer_.lastOdometry(&ref_utime, &ref)) odometry_check_.setReference(ref_utime, ref.x_m, ref.y_m, ref.theta_rad);
  else odometry_check_.reset();
  lcmio::PosePlausibility p;
  p.max_coordinate_m = b.max_odometry_coordinate_m;
  p.max_speed_mps = opt_.pairing.max_odometry_speed_mps;
  p.max_yaw_rate_radps = opt_.pairing.max_odometry_yaw_rate_radps;
  p.confirm_messages = b.jump_confirm_messages;
  if (auto why = odometry_check_.admit(msg.utime, msg.x_m, msg.y_m, msg.theta_rad, p)) return at + *why;
  return std::nullopt;
}

DriverResult SlamDriver::onOdometry(const odometry_t& msg) {
  DriverResult r;
  if (auto why = checkOdometry(msg)) {
    ++stats_.implausible;
    r.refused.push_back({"ODOMETRY", *why});
    return r;
  }
  std::vector<PairEvent> events;
  note(pairer_.addOdometry(msg.utime, Pose2{msg.x_m, msg.y_m, msg.theta_rad}, events), "ODOMETRY", r);
  apply(events, r);
  maybePredict(r);
  return r;
}

DriverResult SlamDriver::onFeatures(const features_t& msg) {
  DriverResult r;
  const double cam_m = std::hypot(msg.camera_position_m[0], msg.camera_position_m[1], msg.camera_position_m[2]);
  if (!(cam_m <= opt_.plausibility.max_camera_offset_m)) {
    ++stats_.implausible;
    r.refused.push_back(
        {"OMNI_FEATURES", "frame seq " + std::to_string(msg.seq) + ": camera_position_m " + num(cam_m) +
                              " m from the robot's origin, more than plausibility.max_camera_offset_m " +
                              num(opt_.plausibility.max_camera_offset_m)});
    return r;
  }
  stats_.features_in += msg.num_features;
  if (!pairer_.odometry().empty())
    odom_utime_at_last_frame_ = std::max(odom_utime_at_last_frame_, pairer_.odometry().newestUtime());
  int64_t skipped = 0;
  Frame frame = toFrame(msg, opt_, &skipped);
  if (static_cast<int>(frame.z.size()) > opt_.max_features_per_frame) {
    // The association's time grows with about the cube of the count (docs/user/slam-process.md).
    ++stats_.frames_too_large;
    r.refused.push_back(
        {"OMNI_FEATURES",
         "frame seq " + std::to_string(msg.seq) + " has " + std::to_string(frame.z.size()) +
             " usable features, more than features.max_per_frame = " + std::to_string(opt_.max_features_per_frame)});
    return r;
  }
  stats_.features_skipped_kind += skipped;
  std::vector<PairEvent> events;
  note(pairer_.addFrame(std::move(frame), events), "OMNI_FEATURES", r);
  apply(events, r);
  return r;
}

DriverResult SlamDriver::finish() {
  DriverResult r;
  std::vector<PairEvent> events;
  note(pairer_.finish(events), "", r);
  apply(events, r);
  return r;
}

void SlamDriver::apply(std::vector<PairEvent>& events, DriverResult& r) {
  for (PairEvent& ev : events) {
    switch (ev.kind) {
      case PairEvent::Kind::kReset:
        if (filter_) {  // the next frame initialises a new filter (new epoch); this one is kept to save
          ++stats_.filter_resets;
          restart_from_ = Estimate{filter_->meanPose(), filter_->poseCovariance(), filter_->bestMap()};
          ended_filter_ = std::move(filter_);
          ended_step_utime_ = last_step_utime_;
        }
        ++epoch_;
        last_step_utime_ = last_frame_utime_ = odom_utime_at_last_frame_ = 0;
        // A new odometry frame: global localisation starts again unless the filter goes on from its
        // last estimate (restart.reinit_from).
        if (start_ && !(restart_from_ && opt_.restart.reinit_from == RestartOptions::ReinitFrom::kLastEstimate)) {
          if (opt_.start_source == SlamProcessOptions::StartSource::kUnknown) start_->restart();
          else start_->resumeTracking();  // the configured start again (lost.policy relocalise)
        }
        break;
      case PairEvent::Kind::kDropped: r.dropped.push_back(ev.reason); break;
      case PairEvent::Kind::kPaired:
        if (auto out = process(ev.frame, ev.odom_O, r)) r.outputs.push_back(std::move(*out));
        break;
    }
  }
}

const slam::FastSlam* SlamDriver::filterToSave(int64_t* utime) const {
  if (filter_) {
    if (utime) *utime = last_step_utime_;
    return filter_.get();
  }
  if (utime) *utime = ended_step_utime_;
  return ended_filter_.get();
}

bool SlamDriver::localising() const {
  return start_ && start_->phase() == GlobalStart::Phase::kLocalising &&
         !(restart_from_ && opt_.restart.reinit_from == RestartOptions::ReinitFrom::kLastEstimate);
}

void SlamDriver::localise(const Frame& frame, const Pose2& odom_O, DriverResult& r) {
  ++stats_.frames_localising;
  const std::optional<GlobalStart::Fix> fix = start_->onFrame(odom_O, frame.z);
  r.localisation.push_back(toLocalisationMessage(start_->status(), frame.utime, localisation_seq_++, frame.seq));
  if (!fix) return;
  ++stats_.localisation_fixes;
  ensureFilter(odom_O, r, &*fix);
  // The fix is this frame's pose (its bearings are in it): the filter steps from the next frame on.
  last_step_utime_ = last_frame_utime_ = frame.utime;
}

void SlamDriver::ensureFilter(const Pose2& odom_O, DriverResult& r, const GlobalStart::Fix* fix) {
  if (filter_) return;
  // Built aside and kept only once initialised: a filter that failed to start must not stay.
  auto filter = std::make_unique<slam::FastSlam>(opt_.filter, opt_.seed + static_cast<std::uint64_t>(epoch_));
  const RestartOptions& ro = opt_.restart;
  if (fix) {  // start_pose.source unknown, or lost: the particles drawn around the localiser's pose
    filter->initialise(fix->pose_W, startMap(), fix->cov);
    r.notes.push_back("localised after " + std::to_string(start_->status().frames) + " frames at (" +
                      num(fix->pose_W.x_m) + " m, " + num(fix->pose_W.y_m) + " m, " + num(fix->pose_W.theta_rad) +
                      " rad), sd " + num(std::sqrt(fix->cov(0, 0))) + " m, " + num(std::sqrt(fix->cov(1, 1))) + " m, " +
                      num(std::sqrt(fix->cov(2, 2))) + " rad: the filter starts there");
  } else if (restart_from_ && ro.reinit_from == RestartOptions::ReinitFrom::kLastEstimate) {
    // After a restart of the inputs: the robot is where the filter last had it, less sure by the
    // motion the restart may have hidden; its map goes on (shared by all particles, ids kept).
    Eigen::Matrix3d cov = restart_from_->cov;
    cov.diagonal() +=
        Eigen::Vector3d(ro.position_sigma_m * ro.position_sigma_m, ro.position_sigma_m * ro.position_sigma_m,
                        ro.heading_sigma_rad * ro.heading_sigma_rad);
    filter->initialise(restart_from_->pose_W, restart_from_->map, cov);
    ++stats_.reinit_last_estimate;
    r.notes.push_back("filter re-initialised from its last estimate (" + num(restart_from_->pose_W.x_m) + " m, " +
                      num(restart_from_->pose_W.y_m) + " m, " + num(restart_from_->pose_W.theta_rad) + " rad; " +
                      std::to_string(restart_from_->map.size()) + " landmarks), widened by " +
                      num(ro.position_sigma_m) + " m, " + num(ro.heading_sigma_rad) + " rad");
  } else {
    // First step of an epoch: the start pose is known (paper 000), all particles at it.
    const Pose2 start_W = opt_.start_source == SlamProcessOptions::StartSource::kFixed ? opt_.start_pose_W : odom_O;
    filter->initialise(start_W, prior_map_);
  }
  filter_ = std::move(filter);
  odom_prev_O_ = odom_O;
  health_.reset();  // the new filter's start is the health's start
  if (lost_) lost_->found();
  startBackEnd(filter_->meanPose(), filter_->poseCovariance());
}

void SlamDriver::startBackEnd(const Pose2& start_W, const Eigen::Matrix3d& start_cov) {
  backend_.reset();
  if (opt_.backend.mode == smoothing::BackEndMode::kOff || !opt_.filter.update_map) return;
  smoothing::GraphOptions g;
  g.motion = opt_.filter.motion;
  g.start = start_W;
  // The gauge: the filter's start, 1 mm / 1 mrad where it is exact.
  g.start_cov = start_cov + Eigen::Vector3d(1e-6, 1e-6, 1e-6).asDiagonal().toDenseMatrix();
  g.ceiling = opt_.backend.ceilingPrior();
  g.calibrate_odometry = opt_.backend.odometry_calibration == smoothing::OdometryCalibration::kScaleAndDrift;
  g.odometry_covariance_at = opt_.backend.odometry_covariance;
  g.covariance_window = opt_.backend.odometry_covariance_window;
  backend_ = std::make_unique<BackEndRunner>(opt_.backend, g, backend_waits_);
}

// Odometry-only steps: only after the filter has started (the first frame fixes the start), only
// when no frame waits for odometry, and only on the odometry's own clock.
void SlamDriver::maybePredict(DriverResult& r) {
  if (opt_.odometry_only_after_us <= 0 || !filter_ || pairer_.pendingFrames() > 0 || pairer_.odometry().empty()) return;
  const int64_t t = pairer_.odometry().newestUtime();
  // Frames still arrive (late ones too, even ones that are dropped): the features process is alive.
  if (t - std::max(last_frame_utime_, odom_utime_at_last_frame_) < opt_.odometry_only_after_us) return;
  if (t - last_step_utime_ < opt_.odometry_only_period_us) return;
  const auto lk = pairer_.odometry().at(t, opt_.pairing.max_odometry_gap_us);
  if (lk.status != OdometryBuffer::Status::kOk) return;
  filter_->predictOnly(odom_prev_O_, lk.pose_O);
  odom_prev_O_ = lk.pose_O;
  last_step_utime_ = t;
  ++stats_.odometry_only_steps;
  FrameOutput out = makeOutput(t, -1, filter_->ess());
  out.odometry_only = true;
  applyHealth(out, lk.pose_O, nullptr);
  r.outputs.push_back(std::move(out));
}

std::optional<FrameOutput> SlamDriver::process(const Frame& frame, const Pose2& odom_O, DriverResult& r) {
  if (filter_ && frame.utime <= last_step_utime_) {
    // An odometry-only step already moved the filter past this frame (it came too late).
    ++stats_.dropped_behind_prediction;
    r.dropped.push_back("frame seq " + std::to_string(frame.seq) + " utime " + std::to_string(frame.utime) +
                        " is not after the last odometry-only step (utime " + std::to_string(last_step_utime_) +
                        "): dropped");
    return std::nullopt;
  }
  if (!filter_ && localising()) {  // start_pose.source unknown: no filter (and no pose) before the fix
    localise(frame, odom_O, r);
    return std::nullopt;
  }
  const bool started = filter_ != nullptr;
  ensureFilter(odom_O, r);
  if (started && !slam::isKeyframe(opt_.filter.keyframes, odom_prev_O_, odom_O, frame.utime - last_step_utime_))
    return betweenKeyframes(frame, odom_O);
  // The particles on filter.threads threads (the process's pool; the same results for any count).
  const slam::StepResult sr = filter_->step(odom_prev_O_, odom_O, frame.z, sharedThreadPool(opt_.filter.threads));
  std::optional<BackEndReport> backend;
  if (backend_)
    backend = backend_->afterStep(*filter_,
                                  {frame.utime, odom_O, filter_->meanPose(), frame.z, sr.landmark_of_measurement, {}});
  odom_prev_O_ = odom_O;
  last_step_utime_ = last_frame_utime_ = frame.utime;
  ++stats_.frames_processed;
  stats_.measurements_rejected += sr.num_rejected;
  if (sr.weights_degenerate) ++stats_.degenerate_weights;

  FrameOutput out = makeOutput(frame.utime, frame.seq, sr.ess);
  if (backend) out.trajectory = trajectoryMessage(*backend, frame, trajectory_seq_++);
  applyHealth(out, odom_O, &sr);
  if (lost_ && lostAt(frame, sr, out, r)) return std::nullopt;
  if ((stats_.frames_processed - 1) % opt_.map_every_n_frames == 0) {  // the first frame has a map
    out.map = toMapMessage(filter_->bestMap(), filter_->bestCandidateCount(), frame.utime, map_seq_++, frame.seq);
  }

  associations_t a = associationsFor(frame);
  for (std::size_t k = 0; k < frame.feature_index.size(); ++k) {
    const std::int64_t id = k < sr.landmark_of_measurement.size() ? sr.landmark_of_measurement[k] : -1;
    const bool refused = k < sr.measurement_refused.size() && sr.measurement_refused[k];
    a.landmark_id[static_cast<std::size_t>(frame.feature_index[k])] = refused   ? +associations_t::NOT_USED
                                                                      : id >= 0 ? id
                                                                                : +associations_t::NOT_ASSOCIATED;
  }
  out.associations = std::move(a);
  return out;
}

const std::vector<slam::Landmark>& SlamDriver::startMap() const {
  return lost_ && opt_.filter.update_map ? lost_->keptMap() : prior_map_;
}

bool SlamDriver::lostAt(const Frame& frame, const slam::StepResult& sr, const FrameOutput& out, DriverResult& r) {
  slam::LostInput in;
  // The map in view: the loaded one when it is fixed, else the best particle's (this run's lamps too).
  std::vector<slam::Landmark> map = opt_.filter.update_map ? filter_->bestMap() : std::vector<slam::Landmark>{};
  const std::vector<slam::Landmark>& in_view = opt_.filter.update_map ? map : prior_map_;
  const Eigen::Vector3d cam_m = frame.z.empty() ? opt_.filter.perception.default_p_CinR_m : frame.z.front().p_CinR_m;
  in.expected =
      slam::expectedLamps(in_view, filter_->meanPose(), cam_m, opt_.filter.perception, opt_.localisation.max_range_m);
  for (const slam::BearingMeasurement& z : frame.z) in.bearings += z.kind == slam::LandmarkKind::kPoint3D;
  in.matched = std::min(sr.num_associated, in.bearings);
  in.map_fixed = !opt_.filter.update_map;
  in.diverged = out.health && out.health->state == static_cast<int8_t>(slam::HealthState::kDiverged);
  const slam::LostVerdict v = lost_->update(in);
  if (!v.lost) {
    if (!v.unexplained && opt_.filter.update_map) lost_->keepMap(std::move(map));
    return false;
  }
  // The frame is answered by STATE_LOST alone: its outputs' sequence numbers are given back.
  --pose_seq_, --particles_seq_, --health_seq_;
  if (out.trajectory) --trajectory_seq_;
  lose(frame, v.reason, r);
  return true;
}

void SlamDriver::lose(const Frame& frame, const std::string& reason, DriverResult& r) {
  ++stats_.lost;
  r.notes.push_back("lost at frame seq " + std::to_string(frame.seq) + ": " + reason +
                    "; global localisation again, in the map as it was at the last explained frame (" +
                    std::to_string(startMap().size()) + " landmarks)");
  slam::LocalisationStatus lost;
  lost.state = slam::LocalisationState::kLost;
  r.localisation.push_back(toLocalisationMessage(lost, frame.utime, localisation_seq_++, frame.seq));
  // The map saved at exit while lost: the kept one, in a filter at the last estimate.
  auto kept = std::make_unique<slam::FastSlam>(opt_.filter, opt_.seed + static_cast<std::uint64_t>(epoch_));
  kept->initialise(filter_->meanPose(), startMap());
  ended_filter_ = std::move(kept);
  ended_step_utime_ = last_step_utime_;
  filter_.reset();
  backend_.reset();
  restart_from_.reset();
  start_->restart(startMap());
}

// A frame between keyframes (filter.keyframes): the filter is not stepped; the outputs are its
// estimate moved by the odometry since the last step, and no measurement of the frame is used.
FrameOutput SlamDriver::betweenKeyframes(const Frame& frame, const Pose2& odom_O) {
  last_frame_utime_ = frame.utime;
  ++stats_.frames_between_keyframes;
  const Pose2 u = slam::odometryIncrement(odom_prev_O_, odom_O);
  FrameOutput out = makeOutput(frame.utime, frame.seq, filter_->ess(), &u);
  if (const auto fallback = health_.fallbackAt(odom_O)) {  // health.policy fallback_odometry while diverged
    ++stats_.health_fallback;
    setPose(out.pose, fallback->first, fallback->second);
  }
  out.associations = associationsFor(frame);
  return out;
}

associations_t SlamDriver::associationsFor(const Frame& frame) {
  associations_t a{};
  a.utime = frame.utime;
  a.seq = associations_seq_++;
  a.input_seq = frame.seq;
  a.num_features = frame.num_features;
  a.landmark_id.assign(static_cast<std::size_t>(frame.num_features), +associations_t::NOT_USED);
  return a;
}

FrameOutput SlamDriver::makeOutput(int64_t utime, int64_t input_seq, double ess, const Pose2* u) {
  FrameOutput out;
  Pose2 mean = filter_->meanPose();
  Eigen::Matrix3d cov = filter_->poseCovariance();
  if (u) {  // moved by the odometry increment u since the last step: x * u, P -> J_x P J_x^T + R
    cov = slam::propagatePoseCovariance(mean, cov, *u, slam::motionCovariance(mean, *u, opt_.filter.motion));
    mean = slam::predictPose(mean, *u);
  }
  pose_t& p = out.pose;
  p.utime = utime;
  p.seq = pose_seq_++;
  p.x_m = mean.x_m;
  p.y_m = mean.y_m;
  p.theta_rad = mean.theta_rad;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) p.covariance[i][j] = cov(i, j);
  p.num_particles = static_cast<int32_t>(filter_->particles().size());
  p.effective_sample_size = ess;
  p.input_seq = input_seq;

  particles_t& q = out.particles;
  q.utime = utime;
  q.seq = particles_seq_++;
  q.input_seq = input_seq;
  // The contract: the sampled poses and their weights before resampling.
  const std::vector<Pose2>& poses = filter_->posesBeforeResampling();
  const std::vector<double>& w = filter_->weightsBeforeResampling();
  q.num_particles = static_cast<int32_t>(poses.size());
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const Pose2 x = u ? slam::predictPose(poses[k], *u) : poses[k];
    q.x_m.push_back(x.x_m);
    q.y_m.push_back(x.y_m);
    q.theta_rad.push_back(x.theta_rad);
    q.weight.push_back(k < w.size() ? w[k] : 1.0 / static_cast<double>(poses.size()));
  }
  return out;
}

void SlamDriver::applyHealth(FrameOutput& out, const Pose2& odom_O, const slam::StepResult* sr) {
  pose_t& p = out.pose;
  slam::HealthInput in;
  in.slam_W = Pose2{p.x_m, p.y_m, p.theta_rad};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) in.slam_cov(i, j) = p.covariance[i][j];
  in.odom_O = odom_O;
  in.num_particles = p.num_particles;
  in.ess = p.effective_sample_size;
  if (sr) {
    in.resampled = sr->resampled;
    in.weights_degenerate = sr->weights_degenerate;
    in.nis = sr->nis;
    in.nis_dof = sr->nis_dof;
  }
  const slam::HealthReport r = health_.update(in);
  if (r.fallback) {  // health.policy fallback_odometry while diverged
    ++stats_.health_fallback;
    setPose(p, r.pose_W, r.pose_cov);
  }
  stats_.health_uncertain += r.state == slam::HealthState::kUncertain;
  stats_.health_diverged += r.state == slam::HealthState::kDiverged;
  slam_health_t& h = out.health.emplace();
  h.utime = p.utime;
  h.seq = health_seq_++;
  h.input_seq = p.input_seq;
  h.state = static_cast<int8_t>(r.state);
  h.reason = r.reason;
  h.fallback = r.fallback;
  h.num_particles = p.num_particles;
  h.effective_sample_size = p.effective_sample_size;
  h.resampled = in.resampled;
  h.nis = r.nis;
  h.nis_dof = r.nis_dof;
  h.nis_window_per_dof = r.nis_window_per_dof;
  h.nis_window_dof = r.nis_window_dof;
  h.nis_lower = r.nis_lower;
  h.nis_upper = r.nis_upper;
  h.window_statistic = r.window_statistic;
  h.window_travel_m = r.window_travel_m;
  h.total_statistic = r.total_statistic;
  h.total_travel_m = r.total_travel_m;
  h.divergence_threshold = r.threshold;
  h.exceedances = r.exceedances;
}

std::string SlamDriver::summary() const {
  const DriverStats& s = stats();
  const PairingStats& p = s.pairing;
  std::ostringstream o;
  o << "frames " << p.frames_in << " processed " << s.frames_processed << " dropped: no_odometry "
    << p.dropped_no_odometry << " odometry_gap " << p.dropped_odometry_gap << " too_old " << p.dropped_too_old
    << " restart " << p.dropped_restart << "; odometry " << p.odometry_in << "; refused: duplicates " << p.duplicates
    << " out_of_order " << p.out_of_order << " stale " << p.stale_after_restart << " too_large " << s.frames_too_large
    << " implausible " << s.implausible << "; restarts " << p.restarts << " filter_resets " << s.filter_resets
    << "; jumps_ahead: taken " << p.forward_jumps << " stray " << p.stray_ahead << "; odometry_jumps "
    << p.odometry_jumps << "; features " << s.features_in << " skipped " << s.features_skipped_kind
    << " rejected_by_filter " << s.measurements_rejected << "; odometry_only_steps " << s.odometry_only_steps
    << " dropped_behind_prediction " << s.dropped_behind_prediction << " degenerate_weights " << s.degenerate_weights
    << "; between_keyframes " << s.frames_between_keyframes << "; health: uncertain " << s.health_uncertain
    << " diverged " << s.health_diverged << " fallback " << s.health_fallback;
  if (start_)
    o << "; localisation: frames " << s.frames_localising << " fixes " << s.localisation_fixes << " "
      << (start_->phase() == GlobalStart::Phase::kTracking ? "tracking"
                                                           : slam::localisationStateName(start_->status().state));
  if (lost_) o << "; lost " << s.lost << (lost_->lost() ? " (now)" : "");
  if (filter_)
    o << "; landmarks " << filter_->bestParticle().map.size() << " candidates " << filter_->bestCandidateCount();
  if (backend_) {
    const BackEndStats& b = backend_->stats();
    o << "; backend: solves " << b.solves_started << " applied " << b.solves_applied << " failed " << b.solves_failed
      << " loop_closures " << b.loop_closures << " outliers_removed " << b.bearings_removed << " waited " << b.waited
      << " late " << b.late;
  }
  return o.str();
}

}  // namespace omnislam::runtime
