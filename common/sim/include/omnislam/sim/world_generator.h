// Random ceiling-light worlds for sweeps (docs/results/world-families.md): a family name and a seed give a
// whole sim::World (lamps, walls, drivable trajectory, sensors), deterministic bit for bit.
//
// Frames and units: world frame W, metres; the hall is the axis-aligned rectangle `hall` of W with
// the floor at z = 0; lamps are horizontal discs at p_LinW_m (z = height above the floor). Angles in
// radians unless the name says _deg. Every random draw comes from one std::mt19937_64 seeded with
// the seed and turned into numbers by this file's own arithmetic (no std:: distributions, whose
// output differs between standard libraries), so the draws do not depend on the library; whether a
// drawn path stays inside the walls is decided with libm's sin / cos, so a seed gives the same
// bytes on the same platform (tested), and almost surely on others.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/sim/world.h"

namespace omnislam::sim {

/// The families of docs/results/world-families.md.
enum class WorldFamily {
  kHalls,      ///< rectangular halls 20-60 m, regular lamp grids (4-10 m) with gaps and extras, flat 3-10 m
  kIrregular,  ///< halls 20-60 m, scattered lamps and close pairs 0.5-1.5 m apart, ceilings 4-7 m
  kCorridors,  ///< corridors 40-80 m long, 2.5-5 m wide, one or two lamp rows, driven out and back
};

/// An independent seed for stream `stream` of a run seeded with `seed` (splitmix64 of both): the
/// world's draws use stream 10 + the family's number, the detector's stream 2 (the odometry keeps the plain seed, as
/// omnislam-odometry --seed), so no two generators start from the same state.
uint64_t deriveSeed(uint64_t seed, uint64_t stream);

/// "halls", "irregular", "corridors"; nothing for another name.
std::optional<WorldFamily> parseWorldFamily(const std::string& name);
std::string worldFamilyName(WorldFamily f);

/// What the caller chooses (not drawn): the sensor rates.
struct GeneratorOptions {
  double image_rate_hz = 1.0;  ///< feature / image frame rate, (0, 100] Hz (the paper: 1 Hz)
  /// Base rate of GROUND_TRUTH_POSE and ODOMETRY (the sports hall's 50 Hz); raised to the next
  /// whole multiple of image_rate_hz when it is not one (30 Hz frames -> 60 Hz truth).
  double min_truth_rate_hz = 50.0;
};

/// The parameters a world was drawn with (for the record and the tests of the ranges).
struct GeneratedParams {
  WorldFamily family = WorldFamily::kHalls;
  uint64_t seed = 0;
  double hall_x_m = 0.0, hall_y_m = 0.0;            ///< hall size along x and y
  double spacing_x_m = 0.0, spacing_y_m = 0.0;      ///< grid spacing (halls, corridors); 0 otherwise
  double ceiling_min_m = 0.0, ceiling_max_m = 0.0;  ///< lowest / highest lamp height
  int lamps_missing = 0;                            ///< grid positions left empty
  int lamps_extra = 0;                              ///< lamps added off the grid
  int close_pairs = 0;                              ///< lamps with a partner 0.5-1.5 m away (irregular)
  int loops = 0;                                    ///< closed loops driven
  double path_m = 0.0;                              ///< trajectory length
};

struct GeneratedWorld {
  World world;
  GeneratedParams params;
};

/// Draws a world of the family from the seed. Throws std::invalid_argument for bad options.
GeneratedWorld generateWorld(WorldFamily family, uint64_t seed, const GeneratorOptions& options = {});

/// The world as a world file (docs/user/world-file.md) that config::loadWorld reads back to the same
/// World; numbers written with 10 significant digits, so the bytes depend only on the World. Writes
/// what generated worlds use: lights (as a list), the Pajdla-Bakstein camera, the trajectory, the
/// wheel odometry noise, the image nuisances and `hall`. `header` lines are written as comments.
std::string worldToYaml(const World& world, const std::vector<std::string>& header = {});

/// The 3D distance from the optical centre beyond which a lamp of radius `radius_m` at `height_m`
/// is not detected by the feature-level detector model (feature_sim.h: the disc's image smaller
/// than min_area_px, or out of the field of view), searched outwards along the horizontal in 5 cm
/// steps; 0 when it is never visible. For the SLAM's perception range (filter.perception.max_range_m).
double detectionRange_m(const World& world, double radius_m, double height_m, double min_area_px);

}  // namespace omnislam::sim
