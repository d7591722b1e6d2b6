// omnislam-smooth: batch or incremental smoothing of a recorded omnislam-slam run (research/smoothing.md). Reads the
// SLAM output log, smooths poses and vertical-line landmarks with the filter's motion noise (from
// its SLAM config) and the association of --associations, and writes a copy of the log with
// SLAM_POSE and SLAM_MAP replaced, for omnislam-eval. Prints a one-line summary on stderr.
#include <CLI/CLI.hpp>

#include <cmath>
#include <iostream>

#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/runtime/slam_config.h"
#include "smooth_log.h"

using namespace omnislam;

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-smooth: batch or incremental smoothing of a recorded SLAM run (vertical-line landmarks)"};
  std::string in, out, config_path, source = "slam";
  std::vector<std::string> sets;
  smooth::SmoothLogOptions opt;
  cli.add_option("log", in, "omnislam-slam output log (ODOMETRY, OMNI_FEATURES, SLAM_POSE, SLAM_MAP, associations)")
      ->required()
      ->check(CLI::ExistingFile);
  cli.add_option("--out", out, "smoothed copy of the log")->required();
  cli.add_option("--config", config_path, "the SLAM config of the run: its filter.motion is the odometry noise")
      ->required()
      ->check(CLI::ExistingFile);
  cli.add_option("--set", sets, "override a config key (repeatable), as omnislam-slam --set");
  cli.add_option(
         "--associations", source,
         "slam: the filter's (SLAM_ASSOCIATIONS); labels: the truth (GROUND_TRUTH_FEATURE_LABELS, diagnosis only)")
      ->check(CLI::IsMember({"slam", "labels"}));
  cli.add_flag("--initial-from-odometry", opt.initial_from_odometry,
               "start from dead reckoning from the first SLAM_POSE instead of the filter's poses");
  cli.add_flag("--incremental", opt.incremental,
               "grow the problem frame by frame from the first SLAM_POSE and publish each frame's pose from its own "
               "solve (causal)");
  double min_parallax_deg = opt.min_parallax_rad * 180.0 / M_PI;
  cli.add_option("--min-rays", opt.min_rays, "--incremental: rays of a landmark before it is added (default 5)")
      ->check(CLI::Range(2, 100000));
  cli.add_option("--min-parallax-deg", min_parallax_deg,
                 "--incremental: ... seen over at least this spread of directions at their crossing (default 7)")
      ->check(omnislam::app::FiniteRange(0.0, 179.0));
  cli.add_option("--cauchy-scale", opt.smoother.cauchy_scale,
                 "robust kernel scale in bearing sigmas (0: least squares)")
      ->check(omnislam::app::FiniteRange(0.0, 1000.0));
  cli.add_option("--max-iterations", opt.smoother.max_iterations, "Levenberg-Marquardt iterations")
      ->check(CLI::Range(1, 100000));
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  return app::runMain("omnislam-smooth", [&]() -> int {
    const auto slam_options = runtime::loadSlamOptions(config_path, sets);
    opt.motion = slam_options.filter.motion;
    opt.max_odometry_gap_us = slam_options.pairing.max_odometry_gap_us;
    opt.progress = [](const std::string& line) { std::cerr << "omnislam-smooth: " << line << std::endl; };
    opt.min_parallax_rad = min_parallax_deg * M_PI / 180.0;
    opt.associations = source == "labels" ? smooth::AssociationSource::kLabels : smooth::AssociationSource::kSlam;
    const auto rep = smooth::smoothLog(in, out, opt);
    for (const auto& p : rep.problems) std::cerr << "omnislam-smooth: skipped " << p << "\n";
    for (const auto& r : rep.restarts) std::cerr << "omnislam-smooth: warning: " << r << "\n";
    std::cerr << "omnislam-smooth: " << rep.poses << " poses, " << rep.odometry_factors << " odometry and "
              << rep.bearing_factors << " bearing factors (" << rep.bearings_downweighted
              << " down-weighted below 0.5), " << rep.landmarks << " landmarks (" << rep.unanchored_landmarks
              << " without an initial position, unused), " << rep.frames_without_odometry
              << " frames without odometry (" << rep.frames_across_odometry_gap << " across a gap over "
              << opt.max_odometry_gap_us / 1e6 << " s); " << rep.solves << " solve(s), the last: cost "
              << rep.result.initial_cost << " -> " << rep.result.final_cost << " in " << rep.result.iterations
              << " iterations" << (rep.result.converged ? "" : " (not converged)") << "\n";
    return app::kOk;
  });
}
