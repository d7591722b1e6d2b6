// The table of PairingOptions (see pairing_options_table.h): one row per key. The rule numbers are
// those of docs/user/slam-process.md, "Pairing rules".
#include "omnislam/runtime/pairing_options_table.h"

namespace omnislam::runtime {

const std::vector<options::Field<PairingOptions>>& pairingFields() {
  using options::integer, options::real, options::seconds;
  using P = PairingOptions;
  constexpr auto kC = options::Bounds::kClosed;
  // One row per key: not reformatted.
  // clang-format off
  static const std::vector<options::Field<P>> t{
      seconds<P>("max_wait_s", &P::max_wait_us, "max_wait_us", 0, 3600, "rule 5: a frame waits for odometry until the frame stream is this far past it"),
      seconds<P>("max_odometry_gap_s", &P::max_odometry_gap_us, "max_odometry_gap_us", 1e-6, 3600, "rule 5: the odometry samples around a frame at most this far apart"),
      seconds<P>("odometry_buffer_s", &P::odometry_buffer_us, "odometry_buffer_us", 0, 36000, "rule 4: odometry kept behind the newest sample (>= max_wait_s)"),
      integer<P>("max_pending_frames", &P::max_pending_frames, "max_pending_frames", 1, 10000, "rule 5: frames waiting for odometry; beyond this the oldest is dropped"),
      seconds<P>("restart_jump_s", &P::restart_jump_us, "restart_jump_us", 1e-6, 1e6, "rules 1, 2: a step back in utime at least this large is a restart once confirmed"),
      integer<P>("restart_confirm_messages", &P::restart_confirm_messages, "restart_confirm_messages", 1, 1000, "rule 2: messages in a row that confirm a restart or a jump ahead (1: the first, once the other stream agrees)"),
      seconds<P>("max_forward_jump_s", &P::max_forward_jump_us, "max_forward_jump_us", 1e-3, 1e6, "rule 2: a message more than this ahead of the newest utime of either stream is a jump ahead"),
      real<P>("max_odometry_speed_mps", &P::max_odometry_speed_mps, "max_odometry_speed_mps", "m/s", 1e-3, 1e3, kC, "rule 3: faster odometry between two samples is a discontinuity (re-based)"),
      real<P>("max_odometry_yaw_rate_degps", &P::max_odometry_yaw_rate_radps, "max_odometry_yaw_rate_radps", "deg/s", 1e-3, 1e5, kC, "rule 3: the same for the turn rate", true),
  };
  // clang-format on
  return t;
}

}  // namespace omnislam::runtime
