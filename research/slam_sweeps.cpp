// The filter's sweeps over simulated scenarios (tests/core/slam_scenarios.h), the figures that
// docs/design/slam-core.md quotes:
//   research_slam_sweeps hall    the sports hall over simulations x filter seeds, Hungarian and ML: map
//                                mean / max error, runs within paper 000's bars, associations.
//                                Environment: NSIM/SIM0 (simulations, first seed), NFS/FS0 (filter
//                                seeds), VERBOSE=1 (one line per run).
//   research_slam_sweeps lines   walls of vertical lines, mapping: final position and heading error of
//                                FastSLAM 2.0 (Hungarian) and 1.0 (ML), with and without
//                                candidates.ray_motion_noise, exact and noisy odometry, seeds 1-5 ("Known
//                                limit"). The sampled association of "Sampled association" left the
//                                core (issue 53), and with it its rows of this sweep.
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <string>
#include <vector>

#include "slam_scenarios.h"

using namespace omnislam;
using namespace omnislam::slam;
using namespace omnislam::slam::scenarios;

namespace {

void hallSweep() {
  FastSlamOptions o;
  const auto env = [](const char* n, int d) { return getenv(n) ? atoi(getenv(n)) : d; };
  const int nsim = env("NSIM", 8), sim0 = env("SIM0", 7), nfs = env("NFS", 5), fs0 = env("FS0", 100);
  for (int method = 0; method < 2; ++method) {
    double sm = 0, smax = 0, worst_mean = 0, worst_max = 0, sfin = 0, srms = 0;
    int n = 0, bad = 0, dup = 0, within = 0, assoc = 0, incons = 0;
    for (int sim = 0; sim < nsim; ++sim) {
      for (int fs = 0; fs < nfs; ++fs) {
        const RunFigures r = runHall(method ? AssociationMethod::kMaximumLikelihood : AssociationMethod::kHungarian,
                                     fs0 + fs, sim0 + sim, nullptr, o);
        if (getenv("VERBOSE")) print(method ? "ML" : "Hungarian", r);
        sm += r.map_mean_err_m;
        smax += r.map_max_err_m;
        worst_mean = std::max(worst_mean, r.map_mean_err_m);
        worst_max = std::max(worst_max, r.map_max_err_m);
        sfin += r.final_pos_err_m;
        srms += r.rms_pos_err_m;
        bad += r.num_matched != 16 || r.num_spurious;
        dup += r.num_duplicates;
        within += r.map_mean_err_m <= 0.48 && r.map_max_err_m <= 1.05;
        assoc += r.num_associations;
        incons += r.num_inconsistent;
        ++n;
      }
    }
    std::cout << (method ? "ML" : "Hungarian") << ": runs " << n << ", map mean error avg " << sm / n << " (worst "
              << worst_mean << "), map max error avg " << smax / n << " (worst " << worst_max
              << "), within 0.48/1.05: " << within << ", final position error avg " << sfin / n
              << ", rms position error avg " << srms / n << ", runs with missing or spurious landmarks " << bad
              << ", duplicates " << dup << ", associations " << assoc << " (inconsistent " << incons << ")\n";
  }
}

void linesSweep() {
  for (int method = 0; method < 2; ++method) {  // FS2 + Hungarian, FS1 + ML
    for (int ray = 0; ray < 2; ++ray) {
      for (int noisy = 0; noisy < 2; ++noisy) {
        FastSlamOptions o = roomLineOptions();
        o.proposal = method > 0 ? Proposal{FastSlam1Proposal{}} : Proposal{FastSlam2Proposal{}};
        o.association = method == 1 ? AssociationMethod::kMaximumLikelihood : AssociationMethod::kHungarian;
        o.candidates.ray_motion_noise = ray != 0;
        std::cout << (method ? "FastSLAM 1.0 + ML" : "FastSLAM 2.0 + Hungarian") << ", ray_motion_noise " << ray
                  << ", odometry " << (noisy ? "noisy" : "exact") << ": final position / heading error";
        for (std::uint64_t seed = 1; seed <= 5; ++seed) {
          const LineRun r = runLines(o, seed, noisy != 0, false);
          std::cout << "  " << std::fixed << std::setprecision(2) << r.final_pos_err_m << " m / "
                    << std::setprecision(1) << r.final_theta_err_deg << " deg";
        }
        std::cout << std::defaultfloat << "\n";
      }
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  const std::string what = argc == 2 ? argv[1] : "";
  if (what == "hall") {
    hallSweep();
  } else if (what == "lines") {
    linesSweep();
  } else {
    std::cerr << "usage: research_slam_sweeps hall|lines\n";
    return 2;
  }
  return 0;
}
