// Options-table rows (omnislam/core/options_field.h) of every kind on a toy struct: the text of
// values and ranges (exact for whole numbers and durations), the range check in the member's units,
// the echo.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "omnislam/core/angles.h"
#include "omnislam/core/options_field.h"

using namespace omnislam;
using namespace omnislam::options;

namespace {

struct Toy {
  double gain = 0.5;
  double angle_rad = 0.1;
  int count = 3;
  bool on = true;
  Eigen::Vector3d offset_m = Eigen::Vector3d(1, 2, 3);
  int mode = 1;
  std::int64_t wait_us = 2'500'000;
  std::uint64_t seed = 7;
  std::string file;
};

const std::vector<std::string>& modeNames() {
  static const std::vector<std::string> n{"off", "slow", "fast"};
  return n;
}

const std::vector<Field<Toy>>& toyFields() {
  static const std::vector<Field<Toy>> t{
      real<Toy>("gain", &Toy::gain, "gain", "", 0.0, 1.0, Bounds::kLowOpen, "a gain"),
      real<Toy>("angle_deg", &Toy::angle_rad, "angle_rad", "deg", -90, 90, Bounds::kClosed, "an angle", true),
      integer<Toy>("count", &Toy::count, "count", 1, 1e6, "a count"),
      flag<Toy>("on", &Toy::on, "on", "a switch"),
      vec3<Toy>("offset_m", &Toy::offset_m, "offset_m", "m", -10, 10, "an offset"),
      enumeration<Toy>(
          "mode", "mode", modeNames(), [](const Toy& t) { return t.mode; }, [](Toy& t, int i) { t.mode = i; },
          "a mode"),
      seconds<Toy>("wait_s", &Toy::wait_us, "wait_us", 1e-6, 3600, "a wait"),
      uint64<Toy>("seed", &Toy::seed, "seed", 0, 9223372036854775807.0, "a seed"),
      path<Toy>("file", &Toy::file, "file", "a file"),
  };
  return t;
}

const Field<Toy>& row(const std::string& key) {
  for (const auto& f : toyFields())
    if (key == f.key) return f;
  throw std::invalid_argument(key);
}

TEST(OptionsField, TextOfNumbersIsExactForWholeNumbersAndDurations) {
  EXPECT_EQ(secondsText(2'500'000), "2.5");
  EXPECT_EQ(secondsText(1), "0.000001");
  EXPECT_EQ(secondsText(0), "0");
  EXPECT_EQ(secondsText(1'000'000'000'000), "1000000");
  EXPECT_EQ(secondsText(-1'500'000), "-1.5");
  EXPECT_EQ(secondsText(std::numeric_limits<std::int64_t>::min()), "-9223372036854.775808");
  EXPECT_EQ(integerText(1e6), "1000000");
  EXPECT_EQ(integerText(9223372036854775807.0), "9223372036854775807");  // 2^63 as a double
  EXPECT_EQ(numberText(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(numberText(0.05), "0.05");
}

TEST(OptionsField, RangesAndValuesAsTheDocsAndTheEchoPrintThem) {
  const Toy toy;
  EXPECT_EQ(rangeText(row("gain")), "(0, 1]");
  EXPECT_EQ(rangeText(row("count")), "[1, 1000000]");
  EXPECT_EQ(rangeText(row("on")), "true, false");
  EXPECT_EQ(rangeText(row("mode")), "off, slow, fast");
  EXPECT_EQ(rangeText(row("wait_s")), "[1e-06, 3600]");
  EXPECT_EQ(rangeText(row("seed")), "[0, 9223372036854775807]");
  EXPECT_EQ(rangeText(row("file")), "path");
  EXPECT_EQ(valueText(row("angle_deg"), toy), numberText(rad2deg(0.1)));
  EXPECT_EQ(valueText(row("offset_m"), toy), "[1, 2, 3]");
  EXPECT_EQ(valueText(row("mode"), toy), "slow");
  EXPECT_EQ(valueText(row("file"), toy), "\"\"");
  EXPECT_EQ(describeFields(toy, toyFields()),
            "gain=0.5 angle_deg=" + numberText(rad2deg(0.1)) +
                " count=3 on=true offset_m=[1, 2, 3] mode=slow wait_s=2.5 seed=7 file=\"\"");
}

TEST(OptionsField, RangeCheckInTheMembersUnits) {
  const Toy ok;
  EXPECT_EQ(checkRanges(ok, toyFields()), "");
  Toy t = ok;
  t.gain = 0.0;  // the open end
  EXPECT_EQ(checkRanges(t, toyFields()), "gain must be in (0, 1], got 0");
  t = ok;
  t.angle_rad = deg2rad(91.0);
  EXPECT_EQ(checkRanges(t, toyFields()).rfind("angle_rad must be in [" + numberText(deg2rad(-90.0)), 0), 0u)
      << checkRanges(t, toyFields());
  t = ok;
  t.wait_us = 0;  // 1e-6 s is 1 us
  EXPECT_EQ(checkRanges(t, toyFields()), "wait_us must be in [1, 3.6e+09], got 0");
  t.wait_us = 1;
  EXPECT_EQ(checkRanges(t, toyFields()), "");
  t.wait_us = 3'600'000'001;
  EXPECT_NE(checkRanges(t, toyFields()), "");
  t = ok;
  t.seed = std::numeric_limits<std::uint64_t>::max();
  EXPECT_EQ(checkRanges(t, toyFields()).rfind("seed must be in ", 0), 0u);
  t = ok;
  t.mode = 3;
  EXPECT_EQ(checkRanges(t, toyFields()), "mode is not a known value");
  t = ok;
  t.offset_m.z() = 11.0;
  EXPECT_EQ(checkRanges(t, toyFields()), "offset_m.z must be in [-10, 10], got 11");
}

}  // namespace
