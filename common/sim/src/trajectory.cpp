// Analytic constant-speed trajectory: see trajectory.h.
#include "omnislam/sim/trajectory.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace omnislam::sim {
namespace {

double segmentDuration(const Segment& s, const TrajectoryOptions& o) {
  switch (s.kind) {
    case Segment::Kind::kStraight: return s.length_m / o.speed_mps;
    case Segment::Kind::kArc: return std::abs(s.angle_rad) * s.radius_m / o.speed_mps;
    case Segment::Kind::kTurn: return std::abs(s.angle_rad) / o.turn_rate_radps;
  }
  return 0.0;
}

/// Pose after driving `tau` seconds into segment `s` from `p0`.
TrajectorySample along(const Segment& s, const TrajectoryOptions& o, const Pose2& p0, double tau) {
  TrajectorySample out;
  switch (s.kind) {
    case Segment::Kind::kStraight: {
      const double d = o.speed_mps * tau;
      out.pose = p0.compose(Pose2{d, 0.0, 0.0});
      out.v_mps = o.speed_mps;
      break;
    }
    case Segment::Kind::kArc: {
      const double sign = s.angle_rad > 0 ? 1.0 : -1.0;
      const double dphi = sign * o.speed_mps * tau / s.radius_m;
      // Chord of the arc in the segment's start frame: centre at (0, sign * r).
      const Pose2 rel{s.radius_m * std::sin(std::abs(dphi)), sign * s.radius_m * (1.0 - std::cos(dphi)), dphi};
      out.pose = p0.compose(rel);
      out.v_mps = o.speed_mps;
      out.omega_radps = sign * o.speed_mps / s.radius_m;
      break;
    }
    case Segment::Kind::kTurn: {
      const double sign = s.angle_rad > 0 ? 1.0 : -1.0;
      out.pose = p0.compose(Pose2{0.0, 0.0, sign * o.turn_rate_radps * tau});
      out.omega_radps = sign * o.turn_rate_radps;
      break;
    }
  }
  return out;
}

}  // namespace

std::optional<std::string> Trajectory::validate(const TrajectoryOptions& o, const std::vector<Segment>& segs) {
  if (!(o.speed_mps > 0.0 && o.speed_mps <= 5.0)) return "speed_mps must be in (0, 5]";
  if (!(o.turn_rate_radps > 0.0 && o.turn_rate_radps <= 5.0)) return "turn_rate_radps must be in (0, 5]";
  if (!(o.start_pause_s >= 0.0)) return "start_pause_s must be >= 0";
  for (size_t i = 0; i < segs.size(); ++i) {
    const Segment& s = segs[i];
    const std::string at = "segment " + std::to_string(i) + ": ";
    if (s.kind == Segment::Kind::kStraight && !(s.length_m > 0.0)) return at + "length_m must be > 0";
    if (s.kind == Segment::Kind::kArc && !(s.radius_m > 0.0)) return at + "radius_m must be > 0";
    if (s.kind != Segment::Kind::kStraight && !(std::abs(s.angle_rad) > 0.0 && std::isfinite(s.angle_rad)))
      return at + "angle_deg must be non-zero";
  }
  return std::nullopt;
}

Trajectory::Trajectory(const TrajectoryOptions& options, std::vector<Segment> segments)
    : opt_(options), segments_(std::move(segments)) {
  if (auto err = validate(opt_, segments_)) throw std::invalid_argument(*err);
  Pose2 p = opt_.start;
  double t = opt_.start_pause_s;
  for (const Segment& s : segments_) {
    const double dur = segmentDuration(s, opt_);
    start_poses_.push_back(p);
    start_times_.push_back(t);
    t += dur;
    end_times_.push_back(t);
    p = along(s, opt_, p, dur).pose;
    if (s.kind == Segment::Kind::kStraight) length_m_ += s.length_m;
    if (s.kind == Segment::Kind::kArc) length_m_ += std::abs(s.angle_rad) * s.radius_m;
  }
}

TrajectorySample Trajectory::at(double t_s) const {
  // NaN fails every comparison below and would index one past the end: it is the start.
  if (segments_.empty() || !(t_s > opt_.start_pause_s)) {
    TrajectorySample s;
    s.pose = opt_.start;
    return s;
  }
  if (t_s >= end_times_.back()) {
    TrajectorySample s;
    s.pose = along(segments_.back(), opt_, start_poses_.back(), end_times_.back() - start_times_.back()).pose;
    return s;
  }
  const size_t i =
      static_cast<size_t>(std::upper_bound(end_times_.begin(), end_times_.end(), t_s) - end_times_.begin());
  return along(segments_[i], opt_, start_poses_[i], t_s - start_times_[i]);
}

double Trajectory::maxYawRate_radps() const {
  double m = 0.0;
  for (const Segment& s : segments_) {
    if (s.kind == Segment::Kind::kArc) m = std::max(m, opt_.speed_mps / s.radius_m);
    if (s.kind == Segment::Kind::kTurn) m = std::max(m, opt_.turn_rate_radps);
  }
  return m;
}

}  // namespace omnislam::sim
