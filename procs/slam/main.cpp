// omnislam-slam: bearing-only FastSLAM (paper 000) on the bus. Subscribes OMNI_FEATURES and
// ODOMETRY, pairs each frame with the odometry interpolated at its utime, runs one filter step and
// publishes SLAM_POSE, SLAM_HEALTH, SLAM_MAP, SLAM_PARTICLES and SLAM_ASSOCIATIONS stamped with the
// frame's utime; with start_pose.source unknown, SLAM_LOCALISATION per frame until localised.
//   live    on an LCM URL, with PROCESS_STATUS;
//   replay  --replay IN.lcm --out OUT.lcm: the same runtime fed with the log's events in order.
// This file is the adapter: flags and config, the bus; the runtime is common/runtime (slam_runtime.h,
// replay.h).
#include <CLI/CLI.hpp>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <system_error>

#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/lcmio/node.h"
#include "omnislam/runtime/slam_config.h"
#include "omnislam/runtime/replay.h"
#include "omnislam/runtime/slam_runtime.h"

using namespace omnislam;
using runtime::DriverResult;

namespace {

/// One result of the runtime on the bus: refusals and dropped frames counted and reported by the
/// node, notes on stderr, the outputs published in order.
void publishAll(lcmio::Node& node, const DriverResult& r) {
  for (const auto& x : r.refused) node.reject(x.channel, x.reason);
  for (const auto& d : r.dropped) node.reject(channels::kOmniFeatures, d);
  for (const auto& n : r.notes) std::cerr << node.tag() << n << std::endl;
  for (const auto& l : r.localisation) node.publish(channels::kSlamLocalisation, l);
  for (const auto& out : r.outputs) {
    node.publish(channels::kSlamPose, out.pose);
    if (out.health) node.publish(channels::kSlamHealth, *out.health);
    if (out.map) node.publish(channels::kSlamMap, *out.map);
    node.publish(channels::kSlamParticles, out.particles);
    if (out.associations) node.publish(channels::kSlamAssociations, *out.associations);
    if (out.trajectory) node.publish(channels::kSlamTrajectory, *out.trajectory);
  }
}

int runLive(const runtime::SlamProcessOptions& opt, std::vector<slam::Landmark> prior, const std::string& url,
            const std::string& name) {
  lcmio::Node node(name, url);
  runtime::SlamRuntime rt(opt, std::move(prior), node.tag());
  rt.setLive();  // a back-end solve never makes the live filter wait
  rt.resume();
  const auto emit = [&](const DriverResult& r) { publishAll(node, r); };
  // The pairing checks time order itself (duplicates and small steps back are refused, a large step
  // back restarts), so the node's own utime check is off; decoding, validation and seq stay.
  lcmio::InputOptions odo_opt;
  odo_opt.require_increasing_utime = false;
  odo_opt.queue_capacity = 5000;  // 50 Hz: a slow filter step must not lose odometry
  lcmio::InputOptions feat_opt;
  feat_opt.require_increasing_utime = false;
  feat_opt.queue_capacity = 200;
  node.subscribe<odometry_t>(
      channels::kOdometry, [&](const odometry_t& m) { rt.onOdometry(m, emit); }, odo_opt);
  node.subscribe<features_t>(
      channels::kOmniFeatures, [&](const features_t& m) { rt.onFeatures(m, emit); }, feat_opt);
  node.setDetail(rt.detail());
  node.publishStatus();
  node.spin({}, [&] { node.setDetail(rt.detail()); });
  node.setState(process_status_t::STATE_STOPPING);
  const bool saved = rt.writeCheckpointNow();
  node.setDetail(rt.detail());
  node.publishStatus();
  std::cerr << node.tag() << "stopped: " << rt.detail() << std::endl;
  rt.saveMap();
  return saved ? app::kOk : app::kFailure;
}

/// Outputs are checked before any work whose result would be lost at the end; the checkpoint's
/// folder is made (a run's log folder may not exist yet).
void checkOutputs(const runtime::SlamProcessOptions& opt, const std::string& out) {
  if (!opt.save_map_path.empty()) lcmio::requireWritableFile(opt.save_map_path, "--save-map (map.save_path)");
  if (!out.empty()) lcmio::requireWritableFile(out, "--out");
  if (!opt.checkpoint_path.empty()) {
    const std::filesystem::path dir = std::filesystem::path(opt.checkpoint_path).parent_path();
    std::error_code ec;
    if (!dir.empty()) std::filesystem::create_directories(dir, ec);
    lcmio::requireWritableFile(opt.checkpoint_path, "--checkpoint (checkpoint.path)");
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-slam: bearing-only FastSLAM on OMNI_FEATURES + ODOMETRY (live, or --replay of a log)"};
  std::string config_path, url, name = "slam", replay, out, save_map, load_map, association;
  uint64_t seed = 0;
  int particles = 0;
  std::vector<std::string> sets;
  bool localise = false, progress = false, no_progress = false;
  cli.add_option("--config", config_path, "SLAM config (YAML, e.g. config/slam/sports_hall.yaml); default: built-in");
  auto* seed_opt = cli.add_option("--seed", seed, "filter seed (overrides the config's seed)")->check(app::SeedRange());
  cli.add_option("--replay", replay, "offline: read this LCM log instead of the bus");
  cli.add_option("--out", out, "offline: write the input events and the outputs to this LCM log");
  cli.add_option("--set", sets,
                 "override a config key: --set filter.resample_ess_fraction=1.0 (repeatable; needs --config)");
  cli.add_option("--save-map", save_map,
                 "write the best particle's map here on exit (atomic; overrides map.save_path)");
  cli.add_option("--load-map", load_map, "start from this saved map (overrides map.load_path)");
  std::string checkpoint;
  double checkpoint_interval_s = 0.0;
  cli.add_option("--checkpoint", checkpoint,
                 "checkpoint file: resume from it when it exists, write it every "
                 "--checkpoint-interval s of data and at SIGINT/SIGTERM (overrides checkpoint.path)");
  cli.add_option("--checkpoint-interval", checkpoint_interval_s,
                 "seconds of data between checkpoints (overrides "
                 "checkpoint.interval_s)")
      ->check(CLI::Range(0.001, 1e6));
  cli.add_flag("--localise", localise, "localisation only: keep the loaded map fixed (needs a map to load)");
  cli.add_option("--association", association, "override filter.association")
      ->check(CLI::IsMember(runtime::associationNames()));
  cli.add_option("--particles", particles, "override filter.particles")->check(CLI::Range(1, 100000));
  cli.add_flag("--progress", progress,
               "offline: print progress (frames, rate, time left) every 2 s (default when stderr is a terminal)");
  cli.add_flag("--no-progress", no_progress, "offline: no progress lines");
  cli.add_option("--url", url, "LCM URL (default: $LCM_DEFAULT_URL)");
  cli.add_option("--name", name, "process name in PROCESS_STATUS");
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  return app::runMain("omnislam-slam", [&]() -> int {
    if (replay.empty() != out.empty()) throw std::invalid_argument("--replay IN.lcm and --out OUT.lcm go together");
    runtime::SlamProcessOptions opt;
    if (!sets.empty() && config_path.empty()) throw std::invalid_argument("--set needs --config FILE");
    if (!config_path.empty()) opt = runtime::loadSlamOptions(config_path, sets);
    if (*seed_opt) opt.seed = seed;
    if (!save_map.empty()) opt.save_map_path = save_map;
    if (!load_map.empty()) opt.load_map_path = load_map;
    if (localise) opt.localisation_only = true;
    if (!association.empty()) opt.filter.association = runtime::associationFromName(association);
    if (particles > 0) opt.filter.num_particles = particles;
    if (!checkpoint.empty()) opt.checkpoint_path = checkpoint;
    if (checkpoint_interval_s > 0.0)
      opt.checkpoint_interval_us = static_cast<int64_t>(std::llround(checkpoint_interval_s * 1e6));
    if (const std::string err = opt.validate(); !err.empty()) throw std::invalid_argument(err);
    checkOutputs(opt, out);
    std::vector<slam::Landmark> prior = runtime::loadPriorMap(opt, "[" + name + "] ");
    std::cerr << "[" << name << "] " << runtime::describe(opt) << std::endl;
    const bool show_progress = !no_progress && (progress || ::isatty(STDERR_FILENO));
    if (replay.empty()) return runLive(opt, std::move(prior), app::lcmUrl(url), name);
    return runtime::runReplay(opt, std::move(prior), {replay, out, show_progress}) ? app::kOk : app::kFailure;
  });
}
