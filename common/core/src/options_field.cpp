// The text forms of options-table values (see options_field.h).
#include "omnislam/core/options_field.h"

#include <sstream>

namespace omnislam::options {

std::string numberText(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string integerText(double v) {
  constexpr double kTwo63 = 9223372036854775808.0;
  if (v >= kTwo63) return std::to_string(std::numeric_limits<std::int64_t>::max());
  if (v <= -kTwo63) return std::to_string(std::numeric_limits<std::int64_t>::min());
  return std::to_string(static_cast<std::int64_t>(v));
}

std::string secondsText(std::int64_t us) {
  const bool negative = us < 0;
  // Magnitude in unsigned arithmetic: -INT64_MIN does not fit an int64.
  const std::uint64_t mag = negative ? 0 - static_cast<std::uint64_t>(us) : static_cast<std::uint64_t>(us);
  std::string frac = std::to_string(mag % 1'000'000);
  frac.insert(0, 6 - frac.size(), '0');
  while (!frac.empty() && frac.back() == '0') frac.pop_back();
  return (negative ? "-" : "") + std::to_string(mag / 1'000'000) + (frac.empty() ? "" : "." + frac);
}

}  // namespace omnislam::options
