// Plausibility of a stream of planar poses: see plausibility.h.
#include "omnislam/lcmio/plausibility.h"

#include <cmath>
#include <sstream>

namespace omnislam::lcmio {

namespace {
std::string num(double v) {
  std::ostringstream o;
  o.precision(6);
  o << v;
  return o.str();
}
double wrapped(double a) { return std::remainder(a, 2.0 * M_PI); }
}  // namespace

std::string PosePlausibility::validate() const {
  if (!(max_coordinate_m > 0.0 && std::isfinite(max_coordinate_m)))
    return "max_coordinate_m must be > 0 and finite, got " + num(max_coordinate_m);
  if (!(max_speed_mps > 0.0 && std::isfinite(max_speed_mps)))
    return "max_speed_mps must be > 0 and finite, got " + num(max_speed_mps);
  if (!(max_yaw_rate_radps > 0.0 && std::isfinite(max_yaw_rate_radps)))
    return "max_yaw_rate_radps must be > 0 and finite, got " + num(max_yaw_rate_radps);
  if (confirm_messages < 1 || confirm_messages > 1000)
    return "confirm_messages must be in [1, 1000], got " + std::to_string(confirm_messages);
  return "";
}

std::optional<std::string> PoseStreamCheck::step(const Sample& from, const Sample& to, const PosePlausibility& opt) {
  if (to.utime <= from.utime) return std::nullopt;  // time order is not this check's
  const double dt_s = static_cast<double>(to.utime - from.utime) * 1e-6;
  const double d_m = std::hypot(to.x_m - from.x_m, to.y_m - from.y_m);
  const double dth = std::abs(wrapped(to.theta_rad - from.theta_rad));
  if (!(d_m <= opt.max_speed_mps * dt_s))
    return "moved " + num(d_m) + " m in " + num(dt_s) + " s, faster than max_speed_mps " + num(opt.max_speed_mps);
  if (!(dth <= opt.max_yaw_rate_radps * dt_s))
    return "turned " + num(dth) + " rad in " + num(dt_s) + " s, faster than max_yaw_rate " +
           num(opt.max_yaw_rate_radps) + " rad/s";
  return std::nullopt;
}

std::optional<std::string> PoseStreamCheck::admit(int64_t utime, double x_m, double y_m, double theta_rad,
                                                  const PosePlausibility& opt) {
  if (!(std::abs(x_m) <= opt.max_coordinate_m && std::abs(y_m) <= opt.max_coordinate_m && std::isfinite(theta_rad)))
    return "pose (" + num(x_m) + " m, " + num(y_m) + " m, " + num(theta_rad) +
           " rad) outside the workspace (|x|, |y| <= " + num(opt.max_coordinate_m) + " m)";
  const Sample s{utime, x_m, y_m, theta_rad};
  if (!have_) {
    have_ = true;
    ref_ = s;
    return std::nullopt;
  }
  const auto why = step(ref_, s, opt);
  if (!why) {
    strays_ += pending_count_;  // the stream went on from the reference: the row was strays
    pending_count_ = 0;
    ref_ = s;
    return std::nullopt;
  }
  const bool continues = pending_count_ > 0 && pending_.utime < utime && !step(pending_, s, opt);
  if (pending_count_ > 0 && !continues) strays_ += pending_count_;
  pending_count_ = continues ? pending_count_ + 1 : 1;
  pending_ = s;
  if (pending_count_ >= opt.confirm_messages) {
    ++jumps_;
    last_jump_ = "pose jumped (" + *why + "), confirmed by " + std::to_string(pending_count_) + " poses in a row";
    pending_count_ = 0;
    ref_ = s;
    return std::nullopt;
  }
  return *why + " (implausible: refused unless " + std::to_string(opt.confirm_messages) +
         " poses in a row agree; this is " + std::to_string(pending_count_) + ")";
}

void PoseStreamCheck::setReference(int64_t utime, double x_m, double y_m, double theta_rad) {
  have_ = true;
  ref_ = Sample{utime, x_m, y_m, theta_rad};
}

}  // namespace omnislam::lcmio
