// Image times of the simulated camera: see image_clock.h.
#include "omnislam/sim/image_clock.h"

#include <cmath>
#include <limits>

namespace omnislam::sim {

ImageClock::ImageClock(int64_t start_utime, double image_rate_hz, double truth_rate_hz)
    : start_utime_(start_utime),
      period_us_(1e6 / image_rate_hz),
      tolerance_us_(std::llround(0.25e6 / truth_rate_hz)),
      next_utime_(start_utime) {}

bool ImageClock::take(int64_t utime) {
  // The difference in uint64: exact for any two int64 with utime < next_utime_ (which may be INT64_MAX).
  if (utime<next_utime_&& static_cast<uint64_t>(next_utime_) - static_cast<uint64_t>(utime)> static_cast<uint64_t>(
          tolerance_us_))
    return false;
  // In double: (utime - start) may not fit int64, and n * period is exact enough to 1 us up to
  // about 1e15 us; beyond that (decades) only the order of the times matters.
  const double since_us = static_cast<double>(utime) - static_cast<double>(start_utime_);
  const double n = std::floor((since_us + static_cast<double>(tolerance_us_)) / period_us_) + 1.0;
  const double next = static_cast<double>(start_utime_) + std::round(n * period_us_);
  next_utime_ = next >= 9.2e18 ? std::numeric_limits<int64_t>::max() : static_cast<int64_t>(next);
  return true;
}

}  // namespace omnislam::sim
