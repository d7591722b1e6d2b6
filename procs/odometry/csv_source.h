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

/// Parses the CSV text (header line "utime,v_mps,omega_radps", then one row per sample, '#'
/// comments allowed). Throws std::invalid_argument naming `source` and the line for a missing
/// column, a non-numeric or non-finite field, or a time that does not increase.
std::vector<WheelSample> parseWheelCsv(const std::string& text, const std::string& source);

}  // namespace omnislam::odometry
