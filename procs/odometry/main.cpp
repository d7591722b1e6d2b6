// omnislam-odometry: publishes ODOMETRY, the cumulative dead-reckoned pose, from
//   sim  noisy encoder integration of the true motion (GROUND_TRUTH_POSE), one message per
//        truth sample (>= 20 Hz), noise from the world file's odometry_noise section (its model:
//        wheel, or paper 002's translate_rotate);
//   csv  a recorded CSV of wheel data (utime,v_mps,omega_radps), integrated and paced by utime.
#include <CLI/CLI.hpp>

#include <chrono>
#include <fstream>
#include <iostream>
#include <sstream>

#include "csv_source.h"
#include "omnislam/config/world_config.h"
#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/node.h"
#include "omnislam/lcmio/pacing.h"
#include "omnislam/lcmio/plausibility_flags.h"
#include "omnislam/lcmio/signals.h"
#include "omnislam/lcmio/truth_stream.h"
#include "omnislam/odometry_t.hpp"
#include "omnislam/sim/odometry_sim.h"

using namespace omnislam;

namespace {

odometry_t makeMsg(int64_t utime, int64_t seq, const Pose2& p, double v, double w) {
  odometry_t m{};
  m.utime = utime;
  m.seq = seq;
  m.x_m = p.x_m;
  m.y_m = p.y_m;
  m.theta_rad = p.theta_rad;
  m.v_mps = v;
  m.omega_radps = w;
  return m;
}

/// What the simulated odometry says of its noise, on stderr and as the node's detail.
void describeNoise(lcmio::Node& node, const sim::World& world, const sim::OdometrySimulator& odo, uint64_t seed) {
  const auto& nz = world.odometry_noise;
  if (nz.model == sim::OdometryModel::kTranslateRotate) {
    std::cerr << node.tag() << "simulating odometry of '" << world.name << "', seed " << seed
              << ": translate-then-rotate model, err_tran " << nz.err_tran_m_per_sqrt_m << " m/sqrt(m), err_rot "
              << nz.err_rot_rad_per_sqrt_rad << " rad/sqrt(rad), err_drift " << nz.err_drift_rad_per_sqrt_m
              << " rad/sqrt(m)" << std::endl;
    node.setDetail("model=translate_rotate err_tran=" + std::to_string(nz.err_tran_m_per_sqrt_m) +
                   " err_rot=" + std::to_string(nz.err_rot_rad_per_sqrt_rad) +
                   " err_drift=" + std::to_string(nz.err_drift_rad_per_sqrt_m));
  } else {
    std::cerr << node.tag() << "simulating odometry of '" << world.name << "', seed " << seed << ": scale error "
              << odo.scaleError() << ", heading drift " << odo.headingDrift_rad_per_m() << " rad/m" << std::endl;
    node.setDetail("scale_error=" + std::to_string(odo.scaleError()) +
                   " heading_drift_rad_per_m=" + std::to_string(odo.headingDrift_rad_per_m()));
  }
}

int runSim(lcmio::Node& node, const std::string& world_path, uint64_t seed, const lcmio::PosePlausibility& plausible) {
  const sim::World world = config::loadWorld(world_path);
  sim::OdometrySimulator odo(world.odometry_noise, seed);
  int64_t seq = 0, last_utime = 0, published = 0;
  Pose2 last;
  lcmio::TruthStreamGate gate(plausible);
  node.subscribe<pose_t>(
      channels::kGroundTruthPose,
      [&](const pose_t& p) {
        const bool new_timeline = seq > 0 && p.utime <= last_utime;
        // Checked before anything changes: a refused pose (thrown) leaves the integration, the check
        // and the channel's time order as they were.
        gate.admit(node, p, new_timeline);
        if (new_timeline) {
          // The node took a new timeline (the simulation run again, a truth log replayed again): a new
          // run, as a new odometry process would see it. Integrating the jump back to the start as one
          // step would "drive" metres in negative time, with a velocity from a negative dt.
          odo = sim::OdometrySimulator(world.odometry_noise, seed);
          seq = 0;
          std::cerr << node.tag() << "GROUND_TRUTH_POSE started a new timeline at utime " << p.utime
                    << ": the odometry starts again (pose, noise draws and seq)" << std::endl;
        }
        const Pose2 now = odo.step(Pose2{p.x_m, p.y_m, p.theta_rad});
        double v = 0.0, w = 0.0;
        if (seq > 0) {
          const double dt = (p.utime - last_utime) * 1e-6;
          const Pose2 d = last.between(now);
          v = d.x_m / dt;
          w = d.theta_rad / dt;
        }
        published += node.publish(channels::kOdometry, makeMsg(p.utime, seq++, now, v, w)) ? 1 : 0;
        last = now;
        last_utime = p.utime;
      },
      lcmio::truthInputOptions());
  node.publishStatus();  // subscribed: announce ourselves (the simulator waits for its consumers)
  describeNoise(node, world, odo, seed);
  node.spin();
  lcmio::reportStopped(node, std::to_string(published) + " messages");
  return app::kOk;
}

int runCsv(lcmio::Node& node, const std::string& path, double speedup) {
  std::ifstream f(path);
  if (!f) throw std::invalid_argument("--csv: cannot read '" + path + "'");
  std::stringstream ss;
  ss << f.rdbuf();
  const auto samples = odometry::parseWheelCsv(ss.str(), path);
  std::cerr << node.tag() << samples.size() << " wheel samples from " << path << std::endl;
  node.setState(process_status_t::STATE_RUNNING);
  Pose2 pose;
  const auto wall0 = std::chrono::steady_clock::now();
  size_t published = 0;
  for (size_t i = 0; i < samples.size() && !lcmio::stopRequested(); ++i) {
    if (i > 0) {
      // Mid-point integration of the previous sample's velocities over the interval.
      const double dt = (samples[i].utime - samples[i - 1].utime) * 1e-6;
      const double ds = samples[i - 1].v_mps * dt, dth = samples[i - 1].omega_radps * dt;
      pose = pose.compose(Pose2{ds * std::cos(0.5 * dth), ds * std::sin(0.5 * dth), dth});
    }
    if (speedup > 0) {
      const auto due =
          lcmio::pacedTime(wall0, static_cast<double>(samples[i].utime - samples[0].utime) * 1e-6, speedup);
      while (!lcmio::stopRequested() && std::chrono::steady_clock::now() < due) node.handleFor(0.005);
      if (lcmio::stopRequested()) break;
    }
    node.publish(channels::kOdometry,
                 makeMsg(samples[i].utime, static_cast<int64_t>(i), pose, samples[i].v_mps, samples[i].omega_radps));
    ++published;
  }
  // FINISHED only when every row was published; stopped by a signal part-way, it says so.
  const bool finished = published == samples.size();
  node.setState(finished ? process_status_t::STATE_FINISHED : process_status_t::STATE_STOPPING);
  node.setDetail((finished ? "finished: " : "interrupted: ") + std::to_string(published) + " of " +
                 std::to_string(samples.size()) + " rows published");
  node.publishStatus();
  std::cerr << node.tag() << (finished ? "finished: " : "interrupted: ") << published << " of " << samples.size()
            << " rows published" << std::endl;
  return app::kOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-odometry: publishes cumulative ODOMETRY from a simulation or a wheel-data CSV"};
  std::string source, world_path, csv, url, name = "odometry";
  uint64_t seed = 1;
  double speedup = 1.0, yaw_rate_degps = 0.0;
  lcmio::PosePlausibility plausible;
  cli.add_option("--source", source, "sim | csv")->required()->check(CLI::IsMember({"sim", "csv"}));
  cli.add_option("--world", world_path, "world file (source sim)");
  cli.add_option("--seed", seed, "seed of the odometry noise (source sim)")->check(app::SeedRange());
  cli.add_option("--csv", csv, "wheel data CSV: utime,v_mps,omega_radps (source csv)");
  cli.add_option("--speedup", speedup, "source csv: replay speed-up, 0 = as fast as possible")
      ->check(omnislam::app::FiniteRange(0.0, 1000.0));
  lcmio::addPlausibilityFlags(cli, plausible, yaw_rate_degps, "source sim: GROUND_TRUTH_POSE poses");
  cli.add_option("--url", url, "LCM URL (default: $LCM_DEFAULT_URL)");
  cli.add_option("--name", name, "process name in PROCESS_STATUS");
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  lcmio::finishPlausibilityFlags(plausible, yaw_rate_degps);
  return app::runMain("omnislam-odometry", [&]() -> int {
    if (source == "sim" && world_path.empty()) throw std::invalid_argument("--source sim needs --world FILE");
    if (source == "csv" && csv.empty()) throw std::invalid_argument("--source csv needs --csv FILE");
    lcmio::Node node(name, app::lcmUrl(url));
    return source == "sim" ? runSim(node, world_path, seed, plausible) : runCsv(node, csv, speedup);
  });
}
