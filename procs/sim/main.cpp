// omnislam-sim: the simulated world's clock. Publishes GROUND_TRUTH_POSE (the true robot pose at
// the world's truth rate) and GROUND_TRUTH_MAP (once per simulated second: the ceiling lights, or
// the room's vertical lines as kind 2 at (x, y, 0)), in simulated time,
// paced at a speed-up of real time. Capture and odometry derive their sensors from this stream.
#include <CLI/CLI.hpp>

#include <chrono>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>
#include <thread>

#include "omnislam/config/world_config.h"
#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/node.h"
#include "omnislam/lcmio/pacing.h"
#include "omnislam/lcmio/signals.h"
#include "omnislam/feature_t.hpp"
#include "omnislam/map_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/sim/trajectory.h"

using namespace omnislam;

namespace {

map_t truthMap(const sim::World& w, const std::vector<sim::RoomLine>& room_lines, int64_t utime, int64_t seq) {
  map_t m{};
  m.utime = utime;
  m.seq = seq;
  m.input_seq = -1;
  for (const sim::Light& L : w.lights) {
    landmark_t l{};
    l.id = L.id;
    for (int i = 0; i < 3; ++i) l.position_m[i] = L.p_LinW_m[i];
    l.type = 0;
    l.times_detected = 0;
    l.kind = feature_t::KIND_CEILING_LIGHT;
    m.landmarks.push_back(l);
  }
  for (const sim::RoomLine& R : room_lines) {
    landmark_t l{};
    l.id = R.id;
    l.position_m[0] = R.p_m.x();
    l.position_m[1] = R.p_m.y();
    l.position_m[2] = 0.0;  // a vertical line: z is meaningless (landmark_t)
    l.type = 0;
    l.times_detected = 0;
    l.kind = feature_t::KIND_VERTICAL_LINE;
    m.landmarks.push_back(l);
  }
  m.num_landmarks = static_cast<int32_t>(m.landmarks.size());
  m.num_candidates = 0;
  return m;
}

std::set<std::string> splitNames(const std::string& csv) {
  std::set<std::string> out;
  std::stringstream ss(csv);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.insert(item);
  return out;
}

// Waits until the named consumers have announced themselves on PROCESS_STATUS, so that nothing is
// published into the void; after wait_timeout_s it says which are missing and starts anyway.
void waitForConsumers(lcmio::Node& node, const std::string& wait_for, double wait_timeout_s) {
  const std::set<std::string> wanted = splitNames(wait_for);
  if (wanted.empty()) return;
  lcmio::InputOptions status_opt;
  status_opt.require_increasing_utime = false;  // several publishers share the channel
  status_opt.track_sequence = false;
  // Shared with the handler: the node keeps the subscription after this function returns.
  auto seen_ptr = std::make_shared<std::set<std::string>>();
  node.subscribe<process_status_t>(
      channels::kProcessStatus, [seen_ptr](const process_status_t& st) { seen_ptr->insert(st.name); }, status_opt);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_timeout_s);
  auto all_seen = [&] {
    for (const auto& n : wanted)
      if (!seen_ptr->count(n)) return false;
    return true;
  };
  node.setDetail("waiting for " + wait_for);
  node.spin([&] { return all_seen() || std::chrono::steady_clock::now() > deadline; });
  if (all_seen()) return;
  std::string missing;
  for (const auto& n : wanted)
    if (!seen_ptr->count(n)) missing += (missing.empty() ? "" : ",") + n;
  std::cerr << node.tag() << "gave up waiting for: " << missing << " (starting anyway)" << std::endl;
}

// Sleeps (handling the bus) until simulated time t is due at the speed-up; at once when speedup is 0.
void waitUntilDue(lcmio::Node& node, std::chrono::steady_clock::time_point wall0, double t, double speedup) {
  if (speedup <= 0) {
    node.handleFor(0.0);
    return;
  }
  const auto due = lcmio::pacedTime(wall0, t, speedup);
  while (!lcmio::stopRequested()) {
    const double left = std::chrono::duration<double>(due - std::chrono::steady_clock::now()).count();
    if (left <= 0) break;
    node.handleFor(std::min(left, 0.05));
  }
}

pose_t truthPose(const sim::TrajectorySample& s, int64_t utime, int64_t seq) {
  pose_t p{};
  p.utime = utime;
  p.seq = seq;
  p.x_m = s.pose.x_m;
  p.y_m = s.pose.y_m;
  p.theta_rad = s.pose.theta_rad;
  p.num_particles = 0;
  p.effective_sample_size = 0;
  p.input_seq = -1;
  return p;
}

// The truth stream from t = 0 to end_s at the world's truth rate, the map once per simulated second.
void publishTruth(lcmio::Node& node, const sim::World& world, const sim::Trajectory& traj,
                  const std::vector<sim::RoomLine>& room_lines, double end_s, double speedup) {
  const double dt = 1.0 / world.truth_rate_hz;
  const int64_t n_steps = static_cast<int64_t>(std::floor(end_s / dt + 1e-9));
  const auto wall0 = std::chrono::steady_clock::now();
  int64_t map_seq = 0;
  const int64_t map_every = std::max<int64_t>(1, std::llround(world.truth_rate_hz));
  for (int64_t k = 0; k <= n_steps && !lcmio::stopRequested(); ++k) {
    const double t = k * dt;
    waitUntilDue(node, wall0, t, speedup);
    const int64_t utime = world.start_utime + static_cast<int64_t>(std::llround(t * 1e6));
    node.publish(channels::kGroundTruthPose, truthPose(traj.at(t), utime, k));
    if (k % map_every != 0) continue;
    node.publish(channels::kGroundTruthMap, truthMap(world, room_lines, utime, map_seq++));
    std::ostringstream d;
    d << "t=" << t << " s of " << end_s;
    node.setDetail(d.str());
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-sim: publishes the simulated world's ground truth in simulated time"};
  std::string world_path, url, name = "sim", wait_for;
  double speedup = 10.0, duration_s = 0.0, wait_timeout_s = 15.0;
  cli.add_option("--world", world_path, "world file (config/worlds/*.yaml)")->required();
  cli.add_option("--url", url, "LCM URL (default: $LCM_DEFAULT_URL)");
  cli.add_option("--name", name, "process name in PROCESS_STATUS");
  cli.add_option("--speedup", speedup, "simulated seconds per real second; 0 = as fast as possible")
      ->check(omnislam::app::FiniteRange(0.0, 1000.0));
  cli.add_option("--duration", duration_s, "stop after this many simulated seconds (0 = whole trajectory)")
      ->check(omnislam::app::FiniteRange(0.0, 1e6));
  cli.add_option("--wait-for", wait_for, "comma-separated process names to wait for (PROCESS_STATUS) before starting");
  cli.add_option("--wait-timeout", wait_timeout_s, "seconds to wait for them")
      ->check(omnislam::app::FiniteRange(0.0, 600.0));
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);

  return app::runMain("omnislam-sim", [&]() -> int {
    const sim::World world = config::loadWorld(world_path);
    const sim::Trajectory traj(world.trajectory_options, world.segments);
    const std::vector<sim::RoomLine> room_lines = world.room ? world.room->lines() : std::vector<sim::RoomLine>{};
    const double end_s = duration_s > 0 ? std::min(duration_s, traj.duration_s()) : traj.duration_s();
    lcmio::Node node(name, app::lcmUrl(url));
    std::cerr << node.tag() << "world '" << world.name
              << "': " << (world.room ? room_lines.size() : world.lights.size())
              << (world.room ? " vertical lines" : " lights") << ", trajectory " << traj.length_m() << " m in "
              << traj.duration_s() << " s (running " << end_s << " s at " << speedup << "x), truth at "
              << world.truth_rate_hz << " Hz" << std::endl;

    waitForConsumers(node, wait_for, wait_timeout_s);
    if (lcmio::stopRequested()) return app::kOk;
    node.setState(process_status_t::STATE_RUNNING);
    publishTruth(node, world, traj, room_lines, end_s, speedup);
    const bool interrupted = lcmio::stopRequested();
    node.setState(interrupted ? process_status_t::STATE_STOPPING : process_status_t::STATE_FINISHED);
    node.setDetail(interrupted ? "interrupted" : "scenario finished");
    node.publishStatus();
    std::cerr << node.tag() << (interrupted ? "interrupted" : "scenario finished") << " after "
              << node.counters().messages_out << " messages" << std::endl;
    return app::kOk;
  });
}
