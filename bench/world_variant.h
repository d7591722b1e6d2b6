// A world file made from another for a live benchmark run (bench_latency, bench_memory): another
// image rate (the truth and odometry rate raised to a whole multiple of it, as omnislam-gen-world
// does: 30 Hz frames -> 60 Hz truth), and a trajectory lengthened to last at least a given time by
// driving it back and forth (out, a half turn on the spot, the same path in reverse, a half turn,
// out again, ...): the robot stays on the path the world was drawn with, inside its walls, and
// sees no new place after the first pass, so the map stops growing. Everything else is the world's.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "omnislam/core/angles.h"
#include "omnislam/sim/trajectory.h"
#include "omnislam/sim/world.h"

namespace omnislam::bench {

/// The truth rate for frames at image_rate_hz: the smallest whole multiple of it at or above
/// min_truth_rate_hz (world_generator.h's rule).
inline double truthRateFor(double image_rate_hz, double min_truth_rate_hz = 50.0) {
  const double k = std::ceil(min_truth_rate_hz / image_rate_hz - 1e-9);
  return std::max(1.0, k) * image_rate_hz;
}

/// The segments driven backwards: reverse order; an arc or a turn on the spot turns the other way.
inline std::vector<sim::Segment> reversedPath(const std::vector<sim::Segment>& segments) {
  std::vector<sim::Segment> back(segments.rbegin(), segments.rend());
  for (sim::Segment& s : back) s.angle_rad = -s.angle_rad;
  return back;
}

/// The trajectory's duration [s] (start pause included).
inline double durationOf(const sim::World& w) { return sim::Trajectory(w.trajectory_options, w.segments).duration_s(); }

/// `world` with frames at image_rate_hz (0: its own rates kept) and its path driven back and forth
/// until the trajectory lasts at least min_duration_s (0: as it is). A path with no segment is kept.
inline sim::World worldVariant(sim::World world, double image_rate_hz, double min_duration_s) {
  if (image_rate_hz > 0.0) {
    world.image_rate_hz = image_rate_hz;
    world.truth_rate_hz = truthRateFor(image_rate_hz);
  }
  if (world.segments.empty()) return world;
  const sim::Segment half_turn{sim::Segment::Kind::kTurn, 0.0, 0.0, kPi};
  const std::vector<sim::Segment> out = world.segments, back = reversedPath(world.segments);
  bool forward = false;
  while (durationOf(world) < min_duration_s) {
    world.segments.push_back(half_turn);
    const auto& leg = forward ? out : back;
    world.segments.insert(world.segments.end(), leg.begin(), leg.end());
    forward = !forward;
  }
  return world;
}

}  // namespace omnislam::bench
