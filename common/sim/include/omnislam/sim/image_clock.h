// When the simulated camera takes its images: at start + round(n * 1e6 / image_rate_hz) us for
// n = 0, 1, ..., on the truth samples the simulator publishes at start + round(k * 1e6 / truth_rate_hz).
// Each image time is computed from its index, so an image period that is not a whole number of
// microseconds (15 Hz: 66666.67 us) does not drift off the truth samples it falls on.
#pragma once

#include <cstdint>

namespace omnislam::sim {

class ImageClock {
 public:
  /// image_rate_hz > 0 and truth_rate_hz > 0 (the world file checks both and that the image rate
  /// divides the truth rate).
  ImageClock(int64_t start_utime, double image_rate_hz, double truth_rate_hz);
  /// True when the truth sample at `utime` [us] is due for an image (it is at or after the next
  /// image time, less a quarter of a truth period for rounding); the clock then moves to the first
  /// image time after it, in one step however far ahead `utime` is (a gap skips its images).
  bool take(int64_t utime);
  /// The next image time [us]; INT64_MAX once the next one would be past the end of int64.
  int64_t nextUtime() const { return next_utime_; }

 private:
  int64_t start_utime_;
  double period_us_;
  int64_t tolerance_us_;
  int64_t next_utime_;
};

}  // namespace omnislam::sim
