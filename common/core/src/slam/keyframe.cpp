// Keyframe selection by odometry travel, rotation and time (see keyframe.h).
#include "omnislam/core/slam/keyframe.h"

#include <cmath>

namespace omnislam::slam {

bool isKeyframe(const KeyframeOptions& o, const Pose2& odom_last_O, const Pose2& odom_now_O, int64_t dt_us) {
  if (!o.skipsFrames()) return true;
  const Pose2 d = odom_last_O.between(odom_now_O);
  if (o.min_travel_m > 0.0 && std::hypot(d.x_m, d.y_m) >= o.min_travel_m) return true;
  if (o.min_rotation_rad > 0.0 && std::abs(d.theta_rad) >= o.min_rotation_rad) return true;
  return o.max_interval_s > 0.0 && static_cast<double>(dt_us) * 1e-6 >= o.max_interval_s;
}

}  // namespace omnislam::slam
