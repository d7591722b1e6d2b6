// The world generator (world_generator.h) and the feature-level simulation (feature_sim.h): same
// seed -> same world file bytes; every generated world valid (lamps inside the hall, trajectory
// inside the walls, heights, sizes and spacings within the family's documented ranges, speeds
// within the paper's limits); the file reads back to the same world; the simulated detector's
// bearings agree with the truth within their published covariance, and its misses and clutter
// follow the model.
#include <gtest/gtest.h>

#include <Eigen/LU>

#include <cmath>
#include <map>

#include "omnislam/config/world_config.h"
#include "omnislam/core/angles.h"
#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/sim/feature_sim.h"
#include "omnislam/sim/world_generator.h"

namespace {

using namespace omnislam;
using namespace omnislam::sim;

constexpr WorldFamily kFamilies[] = {WorldFamily::kHalls, WorldFamily::kIrregular, WorldFamily::kCorridors};
constexpr int kSeeds = 40;

World reread(const World& w) { return config::parseWorld(config::Node::loadString(worldToYaml(w), "test")); }

TEST(WorldGenerator, SameSeedSameBytesOtherSeedOtherWorld) {
  for (WorldFamily f : kFamilies) {
    const std::string a = worldToYaml(generateWorld(f, 7).world);
    EXPECT_EQ(a, worldToYaml(generateWorld(f, 7).world)) << worldFamilyName(f);
    EXPECT_NE(a, worldToYaml(generateWorld(f, 8).world)) << worldFamilyName(f);
  }
  // Families draw from their own streams: seed 7 of two families are not the same hall.
  EXPECT_NE(generateWorld(WorldFamily::kHalls, 7).params.hall_x_m,
            generateWorld(WorldFamily::kIrregular, 7).params.hall_x_m);
}

TEST(WorldGenerator, FileReadsBackToTheSameWorld) {
  for (WorldFamily f : kFamilies)
    for (uint64_t seed = 1; seed <= 5; ++seed) {
      const World w = generateWorld(f, seed).world;
      const World r = reread(w);
      EXPECT_EQ(worldToYaml(r), worldToYaml(w)) << worldFamilyName(f) << " " << seed;
      ASSERT_EQ(r.lights.size(), w.lights.size());
      ASSERT_EQ(r.segments.size(), w.segments.size());
      ASSERT_TRUE(r.hall.has_value());
      for (size_t i = 0; i < w.segments.size(); ++i)
        EXPECT_NEAR(r.segments[i].angle_rad, w.segments[i].angle_rad, 1e-12);
    }
}

struct Range {
  double x_lo, x_hi, y_lo, y_hi, z_lo, z_hi, wall_margin_m;
};

Range rangeOf(WorldFamily f) {
  switch (f) {
    case WorldFamily::kHalls: return {20, 60, 20, 60, 3, 10, 1.0};
    case WorldFamily::kIrregular: return {20, 60, 20, 60, 4, 7, 1.0};
    case WorldFamily::kCorridors: return {40, 80, 2.5, 5, 3, 6, 0.5};
  }
  return {};
}

void expectTrajectoryInside(const World& w, double margin, const std::string& what) {
  const Trajectory t(w.trajectory_options, w.segments);
  EXPECT_LE(w.trajectory_options.speed_mps, 0.30 + 1e-12) << what;  // paper 000: <= 0.30 m/s
  EXPECT_GE(w.trajectory_options.speed_mps, 0.15 - 1e-12) << what;
  EXPECT_LE(t.maxYawRate_radps(), 0.52 + 1e-9) << what;  // paper 000: <= 0.52 rad/s
  int outside = 0;
  for (double s = 0.0; s <= t.duration_s(); s += 0.1) {
    const Pose2 p = t.at(s).pose;
    outside += w.hall->contains(p.x_m, p.y_m, margin - 1e-3) ? 0 : 1;
  }
  EXPECT_EQ(outside, 0) << what;
}

TEST(WorldGenerator, EveryWorldIsValidAndWithinItsFamilysRanges) {
  for (WorldFamily f : kFamilies) {
    const Range r = rangeOf(f);
    int pairs = 0, missing = 0, extra = 0, loops = 0;
    for (uint64_t seed = 1; seed <= kSeeds; ++seed) {
      const GeneratedWorld g = generateWorld(f, seed);
      const World w = reread(g.world);
      const std::string what = worldFamilyName(f) + " seed " + std::to_string(seed);
      ASSERT_TRUE(w.hall.has_value()) << what;
      EXPECT_GE(g.params.hall_x_m, r.x_lo) << what;
      EXPECT_LE(g.params.hall_x_m, r.x_hi) << what;
      EXPECT_GE(g.params.hall_y_m, r.y_lo) << what;
      EXPECT_LE(g.params.hall_y_m, r.y_hi) << what;
      if (f != WorldFamily::kIrregular) {
        EXPECT_GE(g.params.spacing_x_m, 4.0) << what;
        EXPECT_LE(g.params.spacing_x_m, 10.0) << what;
      }
      ASSERT_GE(w.lights.size(), 2u) << what;
      for (const Light& L : w.lights) {
        EXPECT_TRUE(w.hall->contains(L.p_LinW_m.x(), L.p_LinW_m.y())) << what << " lamp " << L.id;
        EXPECT_GE(L.p_LinW_m.z(), r.z_lo - 1e-9) << what;
        EXPECT_LE(L.p_LinW_m.z(), r.z_hi + 1e-9) << what;
        EXPECT_GE(L.radius_m, 0.15 - 1e-9) << what;
        EXPECT_LE(L.radius_m, 0.30 + 1e-9) << what;
      }
      if (f != WorldFamily::kIrregular) {  // flat ceilings
        EXPECT_EQ(g.params.ceiling_min_m, g.params.ceiling_max_m) << what;
      }
      expectTrajectoryInside(w, r.wall_margin_m, what);
      EXPECT_GE(g.params.loops, 1) << what;
      if (f != WorldFamily::kCorridors) {
        EXPECT_GE(g.params.path_m, 80.0) << what;
      }
      pairs += g.params.close_pairs;
      missing += g.params.lamps_missing;
      extra += g.params.lamps_extra;
      loops += g.params.loops;
    }
    // The family's features occur across the seeds.
    if (f == WorldFamily::kIrregular) {
      EXPECT_GT(pairs, kSeeds) << "close pairs";
    }
    if (f == WorldFamily::kHalls) {
      EXPECT_GT(missing, 0);
      EXPECT_GT(extra, 0);
    }
    if (f == WorldFamily::kCorridors) {
      EXPECT_GT(missing, 0);
    }
    EXPECT_GT(loops, kSeeds) << worldFamilyName(f);
  }
}

TEST(WorldGenerator, CloseLampPairsOfIrregularWorldsAreHalfToOneAndAHalfMetresApart) {
  int in_range = 0;
  for (uint64_t seed = 1; seed <= 10; ++seed) {
    const World w = generateWorld(WorldFamily::kIrregular, seed).world;
    for (size_t i = 0; i < w.lights.size(); ++i)
      for (size_t j = i + 1; j < w.lights.size(); ++j) {
        const double d = (w.lights[i].p_LinW_m - w.lights[j].p_LinW_m).head<2>().norm();
        EXPECT_GE(d, 0.5 - 1e-3) << "seed " << seed;  // nothing closer than a close pair
        in_range += d <= 1.5 + 1e-3 ? 1 : 0;
      }
  }
  EXPECT_GT(in_range, 10);
}

TEST(WorldGenerator, TruthRateIsAWholeMultipleOfTheFrameRate) {
  for (double rate : {1.0, 2.0, 10.0, 30.0}) {
    GeneratorOptions o;
    o.image_rate_hz = rate;
    const World w = reread(generateWorld(WorldFamily::kHalls, 3, o).world);  // the parser checks it too
    const double ratio = w.truth_rate_hz / rate;
    EXPECT_NEAR(ratio, std::round(ratio), 1e-9) << rate;
    EXPECT_GE(w.truth_rate_hz, 50.0) << rate;
  }
  GeneratorOptions bad;
  bad.image_rate_hz = 0.0;
  EXPECT_THROW(generateWorld(WorldFamily::kHalls, 1, bad), std::invalid_argument);
  EXPECT_FALSE(parseWorldFamily("hall").has_value());
  EXPECT_EQ(parseWorldFamily("corridors"), WorldFamily::kCorridors);
}

TEST(FeatureSim, SameSeedsSameRunAndOdometryAsTheOdometrySimulator) {
  const World w = reread(generateWorld(WorldFamily::kCorridors, 2).world);
  const SimRun a = simulateFeatures(w, 5, 6), b = simulateFeatures(w, 5, 6);
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (size_t i = 0; i < a.frames.size(); ++i) {
    ASSERT_EQ(a.frames[i].features.size(), b.frames[i].features.size());
    for (size_t j = 0; j < a.frames[i].features.size(); ++j)
      EXPECT_EQ(a.frames[i].features[j].azimuth_rad, b.frames[i].features[j].azimuth_rad);
  }
  OdometrySimulator odo(w.odometry_noise, 5);
  for (const SimTruthStep& s : a.steps) {
    const Pose2 p = odo.step(s.truth);
    ASSERT_EQ(p.x_m, s.odometry.x_m);
    ASSERT_EQ(p.theta_rad, s.odometry.theta_rad);
  }
  const Trajectory t(w.trajectory_options, w.segments);
  EXPECT_NEAR(a.frames.size(), std::floor(t.duration_s() * w.image_rate_hz) + 1, 1.0);
}

TEST(FeatureSim, BearingsAgreeWithTheTruthWithinTheirCovariance) {
  World w = reread(generateWorld(WorldFamily::kHalls, 4).world);
  w.nuisance.false_blobs_per_frame = 0.0;
  const SimRun run = simulateFeatures(w, 1, 2);
  std::map<int64_t, Eigen::Vector3d> lamp;
  for (const Light& L : w.lights) lamp[L.id] = L.p_LinW_m;
  const Eigen::Vector3d cam(w.camera.mounting.x_m, w.camera.mounting.y_m, w.camera.mounting.z_m);
  double nees = 0.0;
  int n = 0;
  for (const SimFrame& f : run.frames) {
    const Pose2& x = run.steps[f.truth_step].truth;
    for (const SimFeature& s : f.features) {
      ASSERT_GE(s.light_id, 1);
      const auto z = slam::predictMeasurement(slam::LandmarkKind::kPoint3D, lamp[s.light_id], x, cam);
      ASSERT_TRUE(z.has_value());
      if ((*z)(1) > 80.0 * kPi / 180.0) continue;  // near the zenith the azimuth is not linear in px
      const Eigen::Vector2d e(wrapAngle(s.azimuth_rad - (*z)(0)), s.elevation_rad - (*z)(1));
      nees += e.dot(s.covariance_rad2.inverse() * e);
      ++n;
    }
  }
  ASSERT_GT(n, 1000);
  EXPECT_NEAR(nees / n, 2.0, 0.2);  // two degrees of freedom
}

TEST(FeatureSim, WindowMissesClutterAndTheSmallestBlob) {
  World w = reread(generateWorld(WorldFamily::kHalls, 5).world);
  w.nuisance.window_wall_enabled = true;
  w.nuisance.window_miss_probability = 1.0;  // every lamp near the windows is missed
  w.nuisance.false_blobs_per_frame = 2.0;
  FeatureSimOptions o;
  const SimRun run = simulateFeatures(w, 1, 2, o);
  int clutter = 0;
  for (const SimFrame& f : run.frames)
    for (const SimFeature& s : f.features) {
      if (s.light_id < 0) {
        ++clutter;
        continue;
      }
      const Light& L = w.lights[static_cast<size_t>(s.light_id - 1)];
      EXPECT_GE(std::abs(L.p_LinW_m.y() - w.nuisance.window_wall_y_m), w.nuisance.window_band_m);
      EXPECT_GE(s.area_px, o.min_area_px);
    }
  const double expected = 2.0 * o.clutter_published_fraction * run.frames.size();
  EXPECT_NEAR(clutter, expected, 4.0 * std::sqrt(expected));  // Poisson: 4 sigma
  // The detection range: a lamp of the world is seen up to it, and not beyond.
  const Light& L = w.lights.front();
  const double range = detectionRange_m(w, L.radius_m, L.p_LinW_m.z(), o.min_area_px);
  ASSERT_GT(range, 5.0);
  const auto cam = makeCamera(w.camera);
  const double dz = L.p_LinW_m.z() - w.camera.mounting.z_m;
  const double dx_in = std::sqrt(range * range - dz * dz) - 0.1, dx_out = dx_in + 0.3;
  const auto in = discImage(*cam, w.camera.mounting, Pose2{}, Eigen::Vector3d(dx_in, 0, L.p_LinW_m.z()), L.radius_m);
  const auto out = discImage(*cam, w.camera.mounting, Pose2{}, Eigen::Vector3d(dx_out, 0, L.p_LinW_m.z()), L.radius_m);
  ASSERT_TRUE(in.has_value());
  EXPECT_GE(in->area_px, o.min_area_px);
  EXPECT_TRUE(!out || out->area_px < o.min_area_px);
}

}  // namespace

// A kidnap (FeatureSimOptions::kidnap): the truth jumps at at_s to the drive's pose at to_s and
// follows the drive from there; the odometry never jumps (it is the drive's motion felt from where the
// robot was: with the same seed it is the run without a kidnap up to at_s, and after it every step
// moves it as much as the truth moves); a kidnap outside the drive is refused.
TEST(FeatureSim, KidnapMovesTheTruthAndNotTheOdometry) {
  const World w = reread(generateWorld(WorldFamily::kHalls, 3).world);
  FeatureSimOptions o;
  o.kidnap = FeatureSimOptions::Kidnap{40.0, 100.0};
  const SimRun plain = simulateFeatures(w, 5, 6), kidnapped = simulateFeatures(w, 5, 6, o);
  const Trajectory traj(w.trajectory_options, w.segments);
  ASSERT_EQ(plain.steps.size(), kidnapped.steps.size());
  const Pose2 carried = traj.at(40.0).pose.between(traj.at(100.0).pose);
  ASSERT_GT(std::hypot(carried.x_m, carried.y_m), 1.0) << "the kidnap moves the robot";
  bool jumped = false;
  for (std::size_t k = 1; k < kidnapped.steps.size(); ++k) {
    const SimTruthStep &s = kidnapped.steps[k], &prev = kidnapped.steps[k - 1];
    if (s.t_s < 40.0) {
      ASSERT_EQ(s.truth.x_m, plain.steps[k].truth.x_m);
      ASSERT_EQ(s.odometry.x_m, plain.steps[k].odometry.x_m);
      continue;
    }
    const double t_drive = std::min(s.t_s - 40.0 + 100.0, traj.duration_s());
    EXPECT_NEAR(s.truth.x_m, traj.at(t_drive).pose.x_m, 1e-9);
    EXPECT_NEAR(s.truth.y_m, traj.at(t_drive).pose.y_m, 1e-9);
    const Pose2 truth_step = prev.truth.between(s.truth), odo_step = prev.odometry.between(s.odometry);
    const double truth_m = std::hypot(truth_step.x_m, truth_step.y_m), odo_m = std::hypot(odo_step.x_m, odo_step.y_m);
    if (prev.t_s < 40.0) {
      jumped = truth_m > 1.0;
    } else {
      EXPECT_NEAR(truth_m, odo_m, 0.02) << "the odometry moves as the truth, up to its noise";
    }
    EXPECT_LT(odo_m, 0.05) << "no jump in the odometry at " << s.t_s << " s";
  }
  EXPECT_TRUE(jumped) << "the truth jumps at the kidnap";
  o.kidnap = FeatureSimOptions::Kidnap{40.0, traj.duration_s() + 1.0};
  EXPECT_THROW(simulateFeatures(w, 5, 6, o), std::invalid_argument);
}
