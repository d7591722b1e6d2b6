// The command-line flags of a PosePlausibility (plausibility.h), shared by the processes that take
// a pose stream (omnislam-odometry and omnislam-capture on GROUND_TRUTH_POSE); docs/user/messages.md,
// "Plausibility". Header-only: the processes link CLI11, the lcmio library does not.
#pragma once

#include <CLI/CLI.hpp>

#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/plausibility.h"

namespace omnislam::lcmio {

/// Adds --max-coordinate-m, --max-speed-mps, --max-yaw-rate-degps and --plausibility-confirm;
/// `yaw_rate_degps` holds the flag's value (degrees, converted with finishPlausibilityFlags).
inline void addPlausibilityFlags(CLI::App& cli, PosePlausibility& p, double& yaw_rate_degps, const std::string& what) {
  yaw_rate_degps = p.max_yaw_rate_radps * 180.0 / M_PI;
  cli.add_option("--max-coordinate-m", p.max_coordinate_m,
                 what + " |x|, |y| beyond this are refused (workspace extent)")
      ->check(app::FiniteRange(1e-3, 1e9))
      ->capture_default_str();
  cli.add_option("--max-speed-mps", p.max_speed_mps, what + " implying a faster motion are refused unless confirmed")
      ->check(app::FiniteRange(1e-3, 1e4))
      ->capture_default_str();
  cli.add_option("--max-yaw-rate-degps", yaw_rate_degps, what + " implying a faster turn are refused unless confirmed")
      ->check(app::FiniteRange(1e-3, 1e6))
      ->capture_default_str();
  cli.add_option("--plausibility-confirm", p.confirm_messages, "poses in a row that confirm a jump")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
}

inline void finishPlausibilityFlags(PosePlausibility& p, double yaw_rate_degps) {
  p.max_yaw_rate_radps = yaw_rate_degps * M_PI / 180.0;
}

}  // namespace omnislam::lcmio
