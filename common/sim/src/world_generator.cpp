// Random ceiling-light worlds: see world_generator.h; ranges and their sources in
// docs/results/world-families.md.
#include "omnislam/sim/world_generator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>
#include <stdexcept>

#include "omnislam/core/angles.h"
#include "omnislam/sim/feature_sim.h"

namespace omnislam::sim {
namespace {

/// Draws from the seed with this file's own arithmetic (the same numbers on every library).
class Draw {
 public:
  explicit Draw(uint64_t seed) : g_(seed) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * static_cast<double>(g_() >> 11) * 0x1.0p-53; }
  int integer(int lo, int hi) { return lo + static_cast<int>(g_() % static_cast<uint64_t>(hi - lo + 1)); }
  bool chance(double p) { return uniform(0.0, 1.0) < p; }

 private:
  std::mt19937_64 g_;
};

double roundTo(double v, double step) { return std::round(v / step) * step; }

// Margins and the robot's limits (docs/results/world-families.md, "Trajectories").
constexpr double kWallMargin_m = 1.0;       ///< the path keeps this far from the walls
constexpr double kCorridorMargin_m = 0.5;   ///< ... in a corridor (2.5 m wide at the least)
constexpr double kMaxYawRate_radps = 0.52;  ///< paper 000: <= 0.52 rad/s
constexpr double kLampMinGap_m = 2.0;       ///< extra / scattered lamps keep this far from the others

struct Path {
  TrajectoryOptions opt;
  std::vector<Segment> segs;
  int loops = 0;
};

Segment straight(double len_m) { return Segment{Segment::Kind::kStraight, roundTo(len_m, 0.001), 0.0, 0.0}; }
Segment arc(double angle_deg, double radius_m) {
  return Segment{Segment::Kind::kArc, 0.0, roundTo(radius_m, 0.001), deg2rad(roundTo(angle_deg, 0.1))};
}
Segment turn(double angle_deg) { return Segment{Segment::Kind::kTurn, 0.0, 0.0, deg2rad(roundTo(angle_deg, 0.1))}; }

/// True when the path `segs` driven from `start` stays `margin` inside the hall (sampled every 5 cm).
bool inside(const HallBounds& h, double margin, const TrajectoryOptions& opt, const Pose2& start,
            const std::vector<Segment>& segs, Pose2* end) {
  TrajectoryOptions o = opt;
  o.start = start;
  o.start_pause_s = 0.0;
  const Trajectory t(o, segs);
  const double step_s = 0.05 / o.speed_mps;
  for (double s = 0.0; s < t.duration_s() + step_s; s += step_s) {
    const Pose2 p = t.at(std::min(s, t.duration_s())).pose;
    if (!h.contains(p.x_m, p.y_m, margin)) return false;
  }
  *end = t.at(t.duration_s()).pose;
  return true;
}

/// Appends `segs` when they stay inside; true then (the pose moves to their end).
bool tryAppend(const HallBounds& h, double margin, Path& path, Pose2& pose, const std::vector<Segment>& segs) {
  Pose2 end;
  if (!inside(h, margin, path.opt, pose, segs, &end)) return false;
  path.segs.insert(path.segs.end(), segs.begin(), segs.end());
  pose = end;
  return true;
}

double minArcRadius(const TrajectoryOptions& o) { return std::max(0.6, o.speed_mps / kMaxYawRate_radps); }

/// The turn on the spot that faces the hall's centre (none when already facing it).
std::vector<Segment> faceCentre(const HallBounds& h, const Pose2& pose) {
  const double cx = 0.5 * (h.x_min_m + h.x_max_m), cy = 0.5 * (h.y_min_m + h.y_max_m);
  const double to_centre_deg = rad2deg(wrapAngle(std::atan2(cy - pose.y_m, cx - pose.x_m) - pose.theta_rad));
  if (std::abs(to_centre_deg) < 0.1) return {};
  return {turn(to_centre_deg)};
}

/// A closed rounded rectangle from the current pose (sides a, b; left or right), back to it; after
/// 10 failed draws, first turned towards the hall's centre, and smaller with every draw.
bool tryLoop(const HallBounds& h, Path& path, Pose2& pose, Draw& d) {
  const double span = std::min(h.x_max_m - h.x_min_m, h.y_max_m - h.y_min_m) - 2.0 * kWallMargin_m;
  constexpr int kAttempts = 30;
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    const double r = d.uniform(minArcRadius(path.opt), 1.5);
    const double shrink = 1.0 - static_cast<double>(attempt) / kAttempts;
    const double a = d.uniform(3.0, std::max(3.5, span * shrink));
    const double b = d.uniform(3.0, std::max(3.5, span * shrink));
    const double sign = d.chance(0.5) ? 1.0 : -1.0;
    std::vector<Segment> loop = attempt >= 10 ? faceCentre(h, pose) : std::vector<Segment>{};
    for (int side = 0; side < 4; ++side) {
      loop.push_back(straight(side % 2 == 0 ? a : b));
      loop.push_back(arc(sign * 90.0, r));
    }
    if (tryAppend(h, kWallMargin_m, path, pose, loop)) {
      ++path.loops;
      return true;
    }
  }
  return false;
}

/// A stretch of 2-5 turns and straights that does not come back.
void explore(const HallBounds& h, Path& path, Pose2& pose, Draw& d) {
  const int moves = d.integer(2, 5);
  for (int m = 0; m < moves; ++m) {
    bool moved = false;
    for (int attempt = 0; attempt < 30 && !moved; ++attempt) {
      std::vector<Segment> segs;
      const double angle = d.uniform(30.0, 180.0) * (d.chance(0.5) ? 1.0 : -1.0);
      if (d.chance(0.5)) segs.push_back(turn(angle));
      else segs.push_back(arc(std::clamp(angle, -120.0, 120.0), d.uniform(minArcRadius(path.opt), 2.0)));
      segs.push_back(straight(d.uniform(2.0, 25.0)));
      moved = tryAppend(h, kWallMargin_m, path, pose, segs);
    }
    if (!moved) {  // cornered: face the hall's centre and go half way there (always inside)
      const double cx = 0.5 * (h.x_min_m + h.x_max_m), cy = 0.5 * (h.y_min_m + h.y_max_m);
      std::vector<Segment> segs = faceCentre(h, pose);
      const double dist = 0.5 * std::hypot(cx - pose.x_m, cy - pose.y_m);
      if (dist > 0.01) segs.push_back(straight(dist));
      if (!segs.empty() && !tryAppend(h, kWallMargin_m, path, pose, segs)) return;
    }
  }
}

double pathLength(const Path& p) {
  double L = 0.0;
  for (const Segment& s : p.segs)
    L += s.kind == Segment::Kind::kStraight ? s.length_m
         : s.kind == Segment::Kind::kArc    ? std::abs(s.angle_rad) * s.radius_m
                                            : 0.0;
  return L;
}

/// Speeds of the paper's robot (docs/results/world-families.md): 0.15-0.30 m/s, turns 10-28.6 deg/s.
TrajectoryOptions drawMotion(Draw& d) {
  TrajectoryOptions o;
  o.speed_mps = roundTo(d.uniform(0.15, 0.30), 0.001);
  o.turn_rate_radps = deg2rad(roundTo(d.uniform(10.0, 28.6), 0.1));
  o.start_pause_s = 0.5;
  return o;
}

/// Loops and exploring stretches, alternately drawn, until the path is 80-160 m long.
Path hallPath(const HallBounds& h, Draw& d) {
  Path path;
  path.opt = drawMotion(d);
  const double x0 = d.uniform(h.x_min_m + 2.0, h.x_max_m - 2.0), y0 = d.uniform(h.y_min_m + 2.0, h.y_max_m - 2.0);
  path.opt.start = Pose2{roundTo(x0, 0.001), roundTo(y0, 0.001), deg2rad(roundTo(d.uniform(-180.0, 180.0), 0.1))};
  const double target_m = d.uniform(80.0, 160.0);
  Pose2 pose = path.opt.start;
  bool first = true;
  while (pathLength(path) < target_m) {
    const double before = pathLength(path);
    if (first || d.chance(0.5)) tryLoop(h, path, pose, d);  // the first leg closes a loop at the start
    else explore(h, path, pose, d);
    first = false;
    if (pathLength(path) == before) explore(h, path, pose, d);
    if (pathLength(path) == before) break;  // nothing fits (never seen; keeps the loop finite)
  }
  return path;
}

/// Out along the corridor's centre line and back, once or twice.
Path corridorPath(const HallBounds& h, Draw& d) {
  Path path;
  path.opt = drawMotion(d);
  const double yc = 0.5 * (h.y_min_m + h.y_max_m);
  const double x0 = roundTo(h.x_min_m + kCorridorMargin_m + d.uniform(0.5, 2.0), 0.001);
  path.opt.start = Pose2{x0, roundTo(yc, 0.001), 0.0};
  const double len = h.x_max_m - kCorridorMargin_m - 0.5 - x0;
  const int trips = d.chance(0.5) ? 2 : 1;
  for (int i = 0; i < trips; ++i) {
    const double sign = d.chance(0.5) ? 1.0 : -1.0;
    path.segs.push_back(straight(len));
    path.segs.push_back(turn(sign * 180.0));
    path.segs.push_back(straight(len));
    path.segs.push_back(turn(-sign * 180.0));
    ++path.loops;
  }
  return path;
}

void addLamp(World& w, double x, double y, double z, double r) {
  Light L;
  L.id = static_cast<int64_t>(w.lights.size()) + 1;
  L.p_LinW_m = Eigen::Vector3d(roundTo(x, 0.001), roundTo(y, 0.001), roundTo(z, 0.001));
  L.radius_m = r;
  w.lights.push_back(L);
}

bool farFromLamps(const World& w, double x, double y, double gap) {
  for (const Light& L : w.lights)
    if (std::hypot(L.p_LinW_m.x() - x, L.p_LinW_m.y() - y) < gap) return false;
  return true;
}

/// A grid of spacing (sx, sy) centred in the hall; each position left empty with p_missing.
void gridLamps(World& w, GeneratedParams& p, const HallBounds& h, double sx, double sy, double z, double r,
               double p_missing, Draw& d) {
  const int nx = std::max(1, static_cast<int>(std::floor((h.x_max_m - h.x_min_m) / sx)));
  const int ny = std::max(1, static_cast<int>(std::floor((h.y_max_m - h.y_min_m) / sy)));
  const double ox = h.x_min_m + 0.5 * ((h.x_max_m - h.x_min_m) - (nx - 1) * sx);
  const double oy = h.y_min_m + 0.5 * ((h.y_max_m - h.y_min_m) - (ny - 1) * sy);
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) {
      if (d.chance(p_missing)) {
        ++p.lamps_missing;
        continue;
      }
      addLamp(w, ox + i * sx, oy + j * sy, z, r);
    }
}

/// Up to n lamps at random places (>= 1 m from the walls, >= kLampMinGap_m from the others).
int scatterLamps(World& w, const HallBounds& h, int n, double z_lo, double z_hi, double r, Draw& d) {
  int added = 0;
  for (int i = 0, tries = 0; i < n && tries < 50 * n; ++tries) {
    const double x = d.uniform(h.x_min_m + 1.0, h.x_max_m - 1.0), y = d.uniform(h.y_min_m + 1.0, h.y_max_m - 1.0);
    const double z = d.uniform(z_lo, z_hi);
    if (!farFromLamps(w, x, y, kLampMinGap_m)) continue;
    addLamp(w, x, y, z, r);
    ++i;
    ++added;
  }
  return added;
}

void hallsFamily(GeneratedWorld& g, Draw& d) {
  World& w = g.world;
  GeneratedParams& p = g.params;
  p.hall_x_m = roundTo(d.uniform(20.0, 60.0), 0.1);
  p.hall_y_m = roundTo(d.uniform(20.0, 60.0), 0.1);
  w.hall = HallBounds{0.0, p.hall_x_m, 0.0, p.hall_y_m};
  p.spacing_x_m = roundTo(d.uniform(4.0, 10.0), 0.01);
  p.spacing_y_m = roundTo(d.uniform(4.0, 10.0), 0.01);
  const double z = roundTo(d.uniform(3.0, 10.0), 0.01);
  const double r = roundTo(d.uniform(0.15, 0.30), 0.01);
  gridLamps(w, p, *w.hall, p.spacing_x_m, p.spacing_y_m, z, r, d.uniform(0.0, 0.15), d);
  const int extra = static_cast<int>(std::lround(d.uniform(0.0, 0.10) * w.lights.size()));
  p.lamps_extra = scatterLamps(w, *w.hall, extra, z, z, r, d);
}

void irregularFamily(GeneratedWorld& g, Draw& d) {
  World& w = g.world;
  GeneratedParams& p = g.params;
  p.hall_x_m = roundTo(d.uniform(20.0, 60.0), 0.1);
  p.hall_y_m = roundTo(d.uniform(20.0, 60.0), 0.1);
  w.hall = HallBounds{0.0, p.hall_x_m, 0.0, p.hall_y_m};
  const double r = roundTo(d.uniform(0.15, 0.30), 0.01);
  const double cell = d.uniform(4.0, 10.0);  // one lamp per cell^2 of ceiling, as the grids' spacing
  const int n = std::max(4, static_cast<int>(std::lround(p.hall_x_m * p.hall_y_m / (cell * cell))));
  p.lamps_extra = scatterLamps(w, *w.hall, n, 4.0, 7.0, r, d);
  const double pair_share = d.uniform(0.2, 0.5);
  const size_t singles = w.lights.size();
  for (size_t i = 0; i < singles; ++i) {
    if (!d.chance(pair_share)) continue;
    const double sep = d.uniform(0.5, 1.5), dir = d.uniform(-kPi, kPi);
    const Eigen::Vector3d& q = w.lights[i].p_LinW_m;
    const double x = q.x() + sep * std::cos(dir), y = q.y() + sep * std::sin(dir);
    if (!w.hall->contains(x, y, 1.0)) continue;
    addLamp(w, x, y, d.uniform(4.0, 7.0), r);
    ++p.close_pairs;
  }
}

void corridorsFamily(GeneratedWorld& g, Draw& d) {
  World& w = g.world;
  GeneratedParams& p = g.params;
  p.hall_x_m = roundTo(d.uniform(40.0, 80.0), 0.1);
  p.hall_y_m = roundTo(d.uniform(2.5, 5.0), 0.01);
  w.hall = HallBounds{0.0, p.hall_x_m, 0.0, p.hall_y_m};
  p.spacing_x_m = roundTo(d.uniform(4.0, 10.0), 0.01);
  const int rows = d.chance(0.5) ? 2 : 1;
  p.spacing_y_m = rows == 2 ? 0.5 * p.hall_y_m : 0.0;
  const double z = roundTo(d.uniform(3.0, 6.0), 0.01);
  const double r = roundTo(d.uniform(0.15, 0.30), 0.01);
  gridLamps(w, p, *w.hall, p.spacing_x_m, rows == 2 ? 0.5 * p.hall_y_m : 2.0 * p.hall_y_m, z, r, d.uniform(0.0, 0.15),
            d);
}

void drawNuisances(World& w, Draw& d) {
  // The sports hall's windows (config/worlds/sports_hall.yaml) along the far wall, in half the worlds.
  w.nuisance.window_wall_enabled = d.chance(0.5);
  w.nuisance.window_wall_y_m = w.hall->y_max_m;
  w.nuisance.window_band_m = 3.0;
  w.nuisance.window_miss_probability = 0.3;
  w.nuisance.false_blobs_per_frame = 0.3;
  w.nuisance.false_blob_radius_px = 3.0;
  w.nuisance.false_blob_peak_grey = 160.0;
}

double truthRate(const GeneratorOptions& o) {
  const double k = std::ceil(o.min_truth_rate_hz / o.image_rate_hz - 1e-9);
  return std::max(1.0, k) * o.image_rate_hz;
}

}  // namespace

uint64_t deriveSeed(uint64_t seed, uint64_t stream) {
  uint64_t z = seed + stream * 0x9E3779B97F4A7C15ull;
  for (int i = 0; i < 2; ++i) {  // splitmix64's finaliser, twice
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
  }
  return z;
}

std::optional<WorldFamily> parseWorldFamily(const std::string& name) {
  if (name == "halls") return WorldFamily::kHalls;
  if (name == "irregular") return WorldFamily::kIrregular;
  if (name == "corridors") return WorldFamily::kCorridors;
  return std::nullopt;
}

std::string worldFamilyName(WorldFamily f) {
  switch (f) {
    case WorldFamily::kHalls: return "halls";
    case WorldFamily::kIrregular: return "irregular";
    case WorldFamily::kCorridors: return "corridors";
  }
  return "?";
}

GeneratedWorld generateWorld(WorldFamily family, uint64_t seed, const GeneratorOptions& options) {
  if (!(options.image_rate_hz > 0.0 && options.image_rate_hz <= 100.0))
    throw std::invalid_argument("world generator: image_rate_hz must be in (0, 100], got " +
                                std::to_string(options.image_rate_hz));
  if (!(options.min_truth_rate_hz >= 20.0 && options.min_truth_rate_hz <= 1000.0))
    throw std::invalid_argument("world generator: min_truth_rate_hz must be in [20, 1000]");
  GeneratedWorld g;
  g.params.family = family;
  g.params.seed = seed;
  Draw d(deriveSeed(seed, 10 + static_cast<uint64_t>(family)));
  if (family == WorldFamily::kHalls) hallsFamily(g, d);
  if (family == WorldFamily::kIrregular) irregularFamily(g, d);
  if (family == WorldFamily::kCorridors) corridorsFamily(g, d);
  World& w = g.world;
  w.name = worldFamilyName(family) + "-" + std::to_string(seed);
  w.image_rate_hz = options.image_rate_hz;
  w.truth_rate_hz = truthRate(options);
  if (w.truth_rate_hz > 1000.0) throw std::invalid_argument("world generator: truth rate above 1000 Hz");
  drawNuisances(w, d);
  double zmin = 1e9, zmax = -1e9;
  for (const Light& L : w.lights) {
    zmin = std::min(zmin, L.p_LinW_m.z());
    zmax = std::max(zmax, L.p_LinW_m.z());
  }
  g.params.ceiling_min_m = zmin;
  g.params.ceiling_max_m = zmax;
  Path path = family == WorldFamily::kCorridors ? corridorPath(*w.hall, d) : hallPath(*w.hall, d);
  w.trajectory_options = path.opt;
  w.segments = path.segs;
  g.params.loops = path.loops;
  g.params.path_m = pathLength(path);
  return g;
}

}  // namespace omnislam::sim
