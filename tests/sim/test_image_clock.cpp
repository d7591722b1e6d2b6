// The simulated camera's image times (sim::ImageClock) on the simulator's truth samples: every
// ratio-th sample, also when the image period is not a whole number of microseconds; a gap skips
// its images; a jump far ahead is one step.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "omnislam/sim/image_clock.h"

namespace {

/// The utime of truth sample k, as omnislam-sim stamps it.
int64_t truthUtime(int64_t start, double truth_rate_hz, int64_t k) {
  const double t = static_cast<double>(k) * (1.0 / truth_rate_hz);
  return start + static_cast<int64_t>(std::llround(t * 1e6));
}

std::vector<int64_t> takenSamples(double truth_hz, double image_hz, int64_t samples) {
  const int64_t start = 1'700'000'000'000'000;
  omnislam::sim::ImageClock clock(start, image_hz, truth_hz);
  std::vector<int64_t> taken;
  for (int64_t k = 0; k < samples; ++k)
    if (clock.take(truthUtime(start, truth_hz, k))) taken.push_back(k);
  return taken;
}

TEST(ImageClock, EveryRatioThTruthSampleIsTaken) {
  // {truth, image, ratio}: 15 Hz is 66666.67 us, not whole microseconds; a per-period sum of the
  // rounded period would drift off the samples (images at k = 0, 2, 5, 7, 9, ...).
  const struct {
    double truth_hz, image_hz;
    int64_t ratio;
  } cases[] = {{30.0, 15.0, 2}, {30.0, 1.5, 20}, {50.0, 1.0, 50}, {1000.0, 3.0, 0}, {90.0, 30.0, 3}, {20.0, 20.0, 1}};
  for (const auto& c : cases) {
    if (c.ratio == 0) continue;  // 1000 / 3 is not whole: the world file refuses it
    const int64_t samples = 100 * c.ratio + 1;
    const std::vector<int64_t> taken = takenSamples(c.truth_hz, c.image_hz, samples);
    ASSERT_EQ(taken.size(), 101u) << c.truth_hz << " / " << c.image_hz << " Hz";
    for (size_t n = 0; n < taken.size(); ++n) EXPECT_EQ(taken[n], static_cast<int64_t>(n) * c.ratio) << c.image_hz;
  }
}

TEST(ImageClock, AGapSkipsItsImagesAndAFarJumpIsOneStep) {
  const int64_t start = 1'000'000;
  omnislam::sim::ImageClock clock(start, 1.0, 50.0);
  EXPECT_FALSE(clock.take(start - 100'000));  // before the first image time
  EXPECT_TRUE(clock.take(start));
  EXPECT_EQ(clock.nextUtime(), start + 1'000'000);
  EXPECT_FALSE(clock.take(start + 500'000));
  // The truth resumes 3.5 s later: one image, then the next whole second after it.
  EXPECT_TRUE(clock.take(start + 3'500'000));
  EXPECT_EQ(clock.nextUtime(), start + 4'000'000);
  // A sample 1 us before the due time (rounding of the truth's stamp) is taken.
  EXPECT_TRUE(clock.take(start + 3'999'999));
  EXPECT_EQ(clock.nextUtime(), start + 5'000'000);
  // Far ahead: computed at once, not one period at a time (~9e12 rounds here).
  EXPECT_TRUE(clock.take(9'000'000'000'000'000'000));
  EXPECT_GT(clock.nextUtime(), 9'000'000'000'000'000'000);
  // Past the end of int64: no more images, and no overflow.
  EXPECT_TRUE(clock.take(std::numeric_limits<int64_t>::max() - 10));
  EXPECT_EQ(clock.nextUtime(), std::numeric_limits<int64_t>::max());
  EXPECT_FALSE(clock.take(0));
}

}  // namespace
