// Reading recorded wheel data for omnislam-odometry: a CSV of utime,v_mps,omega_radps rows.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace omnislam::odometry {

struct WheelSample {
  int64_t utime = 0;
  double v_mps = 0.0;
  double omega_radps = 0.0;
};

/// Largest utime a row may have (microseconds; 4e15 is the year 2096, the bound of world files).
constexpr int64_t kMaxCsvUtime = 4'000'000'000'000'000;

/// Largest |v_mps| and |omega_radps| a row may have: far beyond any wheeled robot, and low enough
/// that the integrated pose stays finite (1e308 m/s made it infinite, and the process stop).
constexpr double kMaxCsvSpeedMps = 100.0;
constexpr double kMaxCsvTurnRateRadps = 100.0;

/// Parses the CSV text (header line "utime,v_mps,omega_radps", then one row per sample, '#'
/// comments allowed). Throws std::invalid_argument naming `source` and the line for a missing or
/// extra column (a trailing comma is one), a non-numeric or non-finite field, a velocity beyond the
/// bounds above, a utime outside 0..kMaxCsvUtime, or a time that does not increase.
std::vector<WheelSample> parseWheelCsv(const std::string& text, const std::string& source);

}  // namespace omnislam::odometry
