// Lost and found: the count test of a tracking filter in a known map; see lost_monitor.h.
#include "omnislam/core/slam/lost_monitor.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/landmark_codec.h"
#include "omnislam/core/slam/options_table.h"

namespace omnislam::slam {

std::string LostOptions::validate() const { return options::checkRanges(*this, options::lostFields()); }

const std::vector<std::string>& lostPolicyNames() {
  static const std::vector<std::string> n{"keep_tracking", "relocalise"};
  return n;
}

int expectedLamps(const std::vector<Landmark>& map, const Pose2& T_WtoR, const Eigen::Vector3d& p_CinR_m,
                  const PerceptionOptions& perception, double max_range_m) {
  const Eigen::Vector3d c_W = cameraCentreInWorld(T_WtoR, p_CinR_m);
  int n = 0;
  for (const Landmark& l : map) {
    if (l.kind != LandmarkKind::kPoint3D) continue;
    if (std::hypot(l.p_LinW_m.x() - c_W.x(), l.p_LinW_m.y() - c_W.y()) > max_range_m) continue;
    n += insidePerceptualRange(l.p_LinW_m, l.kind, c_W, T_WtoR.theta_rad, perception) ? 1 : 0;
  }
  return n;
}

LostMonitor::LostMonitor(const LostOptions& options, const GlobalLocalisationOptions& localisation,
                         double detection_probability)
    : options_(options), localisation_(localisation), p_d_(detection_probability) {
  std::string err = options_.validate();
  if (err.empty() && !(err = localisation_.validate()).empty()) err = "localisation." + err;
  if (err.empty() && !(p_d_ > 0.0 && p_d_ <= 1.0)) err = "detection_probability must be in (0, 1]";
  if (!err.empty()) throw std::invalid_argument("lost options: " + err);
}

LostVerdict LostMonitor::update(const LostInput& in) {
  LostVerdict v;
  const int unexplained_bearings = in.map_fixed ? std::max(in.bearings - in.matched, 0) : 0;
  v.unexplained = !countsExplained(in.matched, in.expected, unexplained_bearings, p_d_, localisation_);
  streak_ = v.unexplained ? streak_ + 1 : 0;
  v.streak = streak_;
  if (in.diverged) {
    v.lost = true;
    v.reason = "the health monitor says diverged";
  } else if (streak_ >= options_.unexplained_frames) {
    v.lost = true;
    v.reason = std::to_string(streak_) +
               " frames in a row unexplained at the filter's pose (last: " + std::to_string(in.matched) + " of " +
               std::to_string(in.expected) + " lamps in view matched, " + std::to_string(in.bearings) + " bearings)";
  }
  lost_ = lost_ || v.lost;
  return v;
}

void LostMonitor::saveState(ByteWriter& w) const {
  w.i32(streak_);
  w.boolean(lost_);
  w.u64(kept_map_.size());
  for (const Landmark& l : kept_map_) putLandmark(w, l);
}

void LostMonitor::loadState(ByteReader& r) {
  const int streak = r.i32("lost streak");
  if (streak < 0) throw StateFormatError("lost streak " + std::to_string(streak) + " is negative");
  const bool lost = r.boolean("lost");
  // A landmark takes at least 8 + 24 + 72 + 4 + 2 + 1 + 24 bytes.
  std::vector<Landmark> map(r.count("lost kept map", std::size_t{1} << 24, 135));
  for (Landmark& l : map) l = getLandmark(r);
  streak_ = streak;
  lost_ = lost;
  kept_map_ = std::move(map);
}

}  // namespace omnislam::slam
