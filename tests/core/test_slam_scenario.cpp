// Whole-filter scenarios (no images, no processes). The sports hall of paper 000 (16 ceiling lights
// at 6.5 m, camera 1.8 m above the floor), a closed rounded-rectangle loop at 0.27 m/s with frames
// at 1 Hz, noisy odometry (~5 %) and bearings (0.3 deg): bounds the map and pose errors with the
// Hungarian association, runs Maximum Likelihood for comparison, and checks bit-exact determinism.
// Walls of vertical lines (paper 002): FastSLAM 2.0 localisation in the true map, and a sweep of
// mapping runs (disabled, figures in docs/slam-core.md).
#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <iomanip>
#include <iostream>
#include <random>
#include <string>
#include <map>

#include "omnislam/core/slam/fastslam.h"

namespace {

using namespace omnislam;
using namespace omnislam::slam;

const Eigen::Vector3d kCamInR(0.0, 0.0, 1.8);
constexpr double kSigmaBearing_rad = 0.3 * kPi / 180.0;

std::vector<Eigen::Vector3d> hallLights() {
  std::vector<Eigen::Vector3d> l;
  for (double x : {4.5, 13.5, 22.5, 31.5}) {
    for (double y : {-5.5, -1.0, 3.5, 8.0}) l.emplace_back(x, y, 6.5);
  }
  return l;
}

// Rounded rectangle: start (6, -3.25, 0), 18 m along +x, left quarter arcs of radius 1 m,
// 7 m along +y, 18 m back, 7 m down. Returns the true pose at arc length s.
struct Segment {
  double length_m, curvature;  // curvature 0 for straight, 1/r for a left arc
};
const std::vector<Segment> kLoop{{18.0, 0.0}, {kPi / 2, 1.0}, {7.0, 0.0}, {kPi / 2, 1.0},
                                 {18.0, 0.0}, {kPi / 2, 1.0}, {7.0, 0.0}, {kPi / 2, 1.0}};

double loopLength() {
  double L = 0.0;
  for (const auto& s : kLoop) L += s.length_m;
  return L;
}

Pose2 poseAt(double s) {
  Pose2 p{6.0, -3.25, 0.0};
  for (const auto& seg : kLoop) {
    const double ds = std::min(s, seg.length_m);
    if (seg.curvature == 0.0) {
      p = p.compose(Pose2{ds, 0.0, 0.0});
    } else {
      const double r = 1.0 / seg.curvature, a = ds * seg.curvature;
      p = p.compose(Pose2{r * std::sin(a), r * (1.0 - std::cos(a)), a});
    }
    s -= ds;
    if (s <= 0.0) break;
  }
  return p;
}

struct Frame {
  Pose2 truth, odom;
  std::vector<BearingMeasurement> z;
  std::vector<int> light;
};

std::vector<Frame> simulateHall(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  const auto lights = hallLights();
  const double L = loopLength(), v = 0.27;
  std::vector<double> s_of_frame;
  for (double s = 0.0; s < L - 1e-9; s += v) s_of_frame.push_back(s);
  s_of_frame.push_back(L);  // back at the start: the loop is closed
  std::vector<Frame> frames;
  Pose2 odom = poseAt(0.0);  // odometry frame O coincides with W at the start
  for (std::size_t k = 0; k < s_of_frame.size(); ++k) {
    Frame f;
    f.truth = poseAt(s_of_frame[k]);
    if (k > 0) {
      const Pose2 u = frames.back().truth.between(f.truth);
      const double d = std::hypot(u.x_m, u.y_m);
      const double scale = 1.0 + 0.05 * n01(rng);  // ~5 % of the distance
      const Pose2 un{u.x_m * scale, u.y_m * scale,
                     u.theta_rad + 0.05 * std::abs(u.theta_rad) * n01(rng) + 0.01 * d * n01(rng)};
      odom = odom.compose(un);
    }
    f.odom = odom;
    for (const auto& l : lights) {
      const auto zt = predictMeasurement(LandmarkKind::kPoint3D, l, f.truth, kCamInR);
      if (!zt || (*zt)(1) < -5.0 * kPi / 180.0) continue;  // 190-degree lens: zenith <= 95 deg
      BearingMeasurement m;
      m.azimuth_rad = wrapAngle((*zt)(0) + kSigmaBearing_rad * n01(rng));
      m.elevation_rad = std::min(kPi / 2, (*zt)(1) + kSigmaBearing_rad * n01(rng));
      m.cov_rad2 = Eigen::Matrix2d::Identity() * kSigmaBearing_rad * kSigmaBearing_rad;
      m.p_CinR_m = kCamInR;
      f.z.push_back(m);
    }
    {
      std::vector<int> idx(f.z.size());
      for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<int>(i);
      std::shuffle(idx.begin(), idx.end(), rng);  // detections come in image order, not map order
      std::vector<BearingMeasurement> zs;
      for (int i : idx) {
        zs.push_back(f.z[i]);
        f.light.push_back(i);
      }
      f.z = zs;
    }
    frames.push_back(std::move(f));
  }
  return frames;
}

struct RunFigures {
  int num_landmarks = 0, num_matched = 0, num_duplicates = 0, num_spurious = 0;
  double map_mean_err_m = 0.0, map_max_err_m = 0.0;
  double final_pos_err_m = 0.0, final_theta_err_rad = 0.0;
  double rms_pos_err_m = 0.0, max_pos_err_m = 0.0, max_theta_err_rad = 0.0;
  double odom_final_pos_err_m = 0.0;
  double seconds = 0.0;
  int steps = 0;
  int num_associations = 0;  ///< measurements associated with map landmarks (best particle, all steps)
  int num_inconsistent = 0;  ///< ... with a landmark that earlier took another light
};

RunFigures runHall(AssociationMethod method, std::uint64_t filter_seed, std::uint64_t sim_seed,
                   FastSlam* out_filter = nullptr, FastSlamOptions o = FastSlamOptions{}) {
  const auto frames = simulateHall(sim_seed);
  o.association = method;
  FastSlam local(o, filter_seed);
  FastSlam& f = out_filter ? *out_filter : local;
  const auto t0 = std::chrono::steady_clock::now();
  f.initialise(frames.front().truth);
  RunFigures r;
  std::map<std::int64_t, int> light_of_landmark;
  double se = 0.0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const Pose2& prev = frames[k == 0 ? 0 : k - 1].odom;
    const StepResult sr = f.step(prev, frames[k].odom, frames[k].z);
    // Association check on the best particle: a landmark id must always be the same light.
    for (std::size_t i = 0; i < sr.landmark_of_measurement.size(); ++i) {
      const std::int64_t id = sr.landmark_of_measurement[i];
      if (id < 0) continue;
      ++r.num_associations;
      const auto [it, inserted] = light_of_landmark.emplace(id, frames[k].light[i]);
      if (!inserted && it->second != frames[k].light[i]) {
        ++r.num_inconsistent;
        it->second = frames[k].light[i];
      }
    }
    const Pose2 m = f.meanPose();
    const double e = std::hypot(m.x_m - frames[k].truth.x_m, m.y_m - frames[k].truth.y_m);
    se += e * e;
    r.max_pos_err_m = std::max(r.max_pos_err_m, e);
    r.max_theta_err_rad = std::max(r.max_theta_err_rad, std::abs(wrapAngle(m.theta_rad - frames[k].truth.theta_rad)));
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.steps = static_cast<int>(frames.size());
  r.rms_pos_err_m = std::sqrt(se / frames.size());
  const Pose2 m = f.meanPose(), t = frames.back().truth;
  r.final_pos_err_m = std::hypot(m.x_m - t.x_m, m.y_m - t.y_m);
  r.final_theta_err_rad = std::abs(wrapAngle(m.theta_rad - t.theta_rad));
  r.odom_final_pos_err_m = std::hypot(frames.back().odom.x_m - t.x_m, frames.back().odom.y_m - t.y_m);

  // Map: each landmark to its nearest light (within 2 m); a second landmark on a light is a duplicate.
  const auto lights = hallLights();
  const auto map = f.bestMap();
  r.num_landmarks = static_cast<int>(map.size());
  std::vector<double> best(lights.size(), 1e9);
  std::vector<int> count(lights.size(), 0);
  for (const auto& lm : map) {
    int li = -1;
    double d = 2.0;
    for (std::size_t i = 0; i < lights.size(); ++i) {
      const double di = (lm.p_LinW_m - lights[i]).norm();
      if (di < d) {
        d = di;
        li = static_cast<int>(i);
      }
    }
    if (li < 0) {
      ++r.num_spurious;
      continue;
    }
    ++count[li];
    best[li] = std::min(best[li], d);
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < lights.size(); ++i) {
    if (count[i] == 0) continue;
    ++r.num_matched;
    r.num_duplicates += count[i] - 1;
    sum += best[i];
    r.map_max_err_m = std::max(r.map_max_err_m, best[i]);
  }
  r.map_mean_err_m = r.num_matched ? sum / r.num_matched : 0.0;
  return r;
}

void print(const char* name, const RunFigures& r) {
  std::cout << "[hall " << name << "] steps " << r.steps << ", " << r.seconds << " s; landmarks " << r.num_landmarks
            << " (matched " << r.num_matched << "/16, duplicates " << r.num_duplicates << ", spurious "
            << r.num_spurious << "); map error mean " << r.map_mean_err_m << " m, max " << r.map_max_err_m
            << " m; pose error final " << r.final_pos_err_m << " m / " << r.final_theta_err_rad
            << " rad, rms " << r.rms_pos_err_m << " m, max " << r.max_pos_err_m << " m / " << r.max_theta_err_rad
            << " rad; odometry-only final error " << r.odom_final_pos_err_m << " m; associations "
            << r.num_associations << ", inconsistent " << r.num_inconsistent << "\n";
}

// Bounds in the spirit of paper 000 (Table I: mean 0.48 m, max 1.05 m over the map; angle error
// under 0.087 rad). Our simulated errors are dominated by the scale that bearing-only SLAM takes
// from the first metres of odometry (all landmarks share it), so they vary with the seeds; the
// fixed seeds below are the first ones tried, not the best (see docs/slam-core.md for a sweep).
/// Paper 000's map bars on one run of the hall: every light once, nothing spurious, map mean and
/// max error and the largest heading error within Table I's figures.
void expectMapWithinPaperBars(const RunFigures& r, std::uint64_t seed) {
  EXPECT_EQ(r.num_matched, 16) << seed;
  EXPECT_EQ(r.num_duplicates, 0) << seed;
  EXPECT_EQ(r.num_spurious, 0) << seed;
  EXPECT_LE(r.map_mean_err_m, 0.48) << seed;
  EXPECT_LE(r.map_max_err_m, 1.05) << seed;
  EXPECT_LE(r.max_theta_err_rad, 0.087) << seed;
}

TEST(slam_Scenario, HallHungarian) {
  const RunFigures r = runHall(AssociationMethod::kHungarian, 1, 2024);
  print("Hungarian seed 1", r);
  EXPECT_EQ(r.num_matched, 16);
  EXPECT_EQ(r.num_duplicates, 0);
  EXPECT_EQ(r.num_spurious, 0);
  EXPECT_LE(r.map_mean_err_m, 0.48);
  EXPECT_LE(r.map_max_err_m, 1.05);
  EXPECT_LE(r.final_pos_err_m, 0.3);   // back at the start, the loop is closed
  EXPECT_LE(r.max_theta_err_rad, 0.087);
  EXPECT_LE(r.rms_pos_err_m, 0.5);
  EXPECT_LT(r.final_pos_err_m, r.odom_final_pos_err_m);
  EXPECT_EQ(r.num_inconsistent, 0);
}

TEST(slam_Scenario, HallHungarianSeveralFilterSeeds) {
  // Like the paper's Fig. 7: the same data, several seeds of the filter.
  double sum_mean = 0.0;
  for (std::uint64_t seed = 2; seed <= 5; ++seed) {
    const RunFigures r = runHall(AssociationMethod::kHungarian, seed, 2024);
    print(("Hungarian seed " + std::to_string(seed)).c_str(), r);
    expectMapWithinPaperBars(r, seed);
    EXPECT_EQ(r.num_inconsistent, 0) << seed;
    sum_mean += r.map_mean_err_m;
  }
  EXPECT_LE(sum_mean / 4, 0.35);
}

TEST(slam_Scenario, HallMaximumLikelihood) {
  // The ML baseline maps the hall as well as the Hungarian method (the same bars; measured: 16/16, map mean 0.11-0.27 m). The paper's finding that
  // ML loses loop closures does not reproduce in this hall (docs/slam-results.md, "Hungarian vs ML").
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const RunFigures r = runHall(AssociationMethod::kMaximumLikelihood, seed, 2024);
    print(("ML seed " + std::to_string(seed)).c_str(), r);
    expectMapWithinPaperBars(r, seed);
    // ML decides each measurement alone and so at times gives two of one frame to one landmark
    // (measured: 2 per run; the joint assignment never does): the baseline is not the Hungarian
    // method under another name.
    EXPECT_GT(r.num_inconsistent, 0) << seed;
  }
}

TEST(slam_Scenario, DeterministicBitForBit) {
  FastSlamOptions o;
  FastSlam a(o, 77), b(o, 77), c(o, 78);
  runHall(AssociationMethod::kHungarian, 77, 2024, &a);
  runHall(AssociationMethod::kHungarian, 77, 2024, &b);
  runHall(AssociationMethod::kHungarian, 78, 2024, &c);
  const auto same = [](double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; };
  ASSERT_EQ(a.particles().size(), b.particles().size());
  bool differs_from_c = false;
  for (std::size_t k = 0; k < a.particles().size(); ++k) {
    const Particle& pa = a.particles()[k];
    const Particle& pb = b.particles()[k];
    EXPECT_TRUE(same(pa.pose.x_m, pb.pose.x_m) && same(pa.pose.y_m, pb.pose.y_m) &&
                same(pa.pose.theta_rad, pb.pose.theta_rad))
        << k;
    EXPECT_TRUE(same(a.particleWeights()[k], b.particleWeights()[k]));
    const auto la = pa.map.landmarks(), lb = pb.map.landmarks();
    ASSERT_EQ(la.size(), lb.size());
    for (std::size_t i = 0; i < la.size(); ++i) {
      EXPECT_EQ(la[i].id, lb[i].id);
      EXPECT_EQ(la[i].counter, lb[i].counter);
      EXPECT_EQ(std::memcmp(la[i].p_LinW_m.data(), lb[i].p_LinW_m.data(), 3 * sizeof(double)), 0);
      EXPECT_EQ(std::memcmp(la[i].cov_LinW_m2.data(), lb[i].cov_LinW_m2.data(), 9 * sizeof(double)), 0);
    }
    EXPECT_EQ(pa.candidates.size(), pb.candidates.size());
    differs_from_c |= !same(pa.pose.x_m, c.particles()[k].pose.x_m);
  }
  EXPECT_TRUE(same(a.ess(), b.ess()));
  EXPECT_EQ(a.bestParticleIndex(), b.bestParticleIndex());
  EXPECT_TRUE(differs_from_c) << "another seed must give another run";
}

// A sweep over simulations and filter seeds (the figures quoted in docs/slam-core.md). Run with
//   core_test_slam_scenario --gtest_also_run_disabled_tests --gtest_filter='*Sweep*'
// Environment: NSIM/SIM0 (simulations, first seed), NFS/FS0 (filter seeds), VERBOSE=1.
TEST(slam_Scenario, DISABLED_Sweep) {
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

// ---------------------------------------------------------------------------------------------
// Vertical lines (paper 002's landmarks, azimuth only): two walls of lines 0.7 m apart (y = 0 and
// y = 4, offset by 0.35 m), a straight 7 m path at y = 1.2 in 10 cm steps, camera 0.5 m up, the
// room's translate-then-rotate motion noise (err_tran 0.03 m/sqrt(m), err_rot 0.05, err_drift
// 0.02 rad/sqrt(m)) and bearings with 0.1 deg noise (docs/slam-core.md, "Known limit").
struct LineRun {
  double final_pos_err_m = 0.0, final_theta_err_deg = 0.0, max_theta_err_deg = 0.0;
  std::size_t num_landmarks = 0;
};

FastSlamOptions roomLineOptions() {
  FastSlamOptions o;
  o.num_particles = 100;
  o.resample_ess_fraction = 0.5;
  o.inflate_azimuth_near_zenith = false;
  o.map_cell_size_m = 2.0;
  auto& m = o.motion;
  m.model = MotionNoiseModel::kTranslateThenRotate;
  m.err_tran_per_m = m.err_rot_per_rad = m.err_drift_rad_per_m = 0.0;
  m.err_tran_per_sqrt_m = 0.03;
  m.err_rot_per_sqrt_rad = 0.05;
  m.err_drift_rad_per_sqrt_m = 0.02;
  auto& p = o.perception;
  p.min_elevation_rad = -kPi / 2;
  p.min_range_m = 0.3;
  p.detection_probability = 0.75;
  p.association_margin_m = 0.5;
  auto& c = o.candidates;
  c.ncross_valid = 3;
  c.require_above_camera = false;
  c.d_min_m = 100.0;
  c.initial_cov_diag_m2 = Eigen::Vector3d::Constant(0.0004);
  return o;
}

std::vector<Eigen::Vector3d> wallLines() {
  std::vector<Eigen::Vector3d> lines;
  for (double x = 0.3; x < 10.0; x += 0.7) {
    lines.emplace_back(x, 0.0, 0.0);
    lines.emplace_back(x + 0.35, 4.0, 0.0);
  }
  return lines;
}

LineRun runLines(FastSlamOptions o, std::uint64_t seed, bool odometry_noise, bool prior_map) {
  const auto lines = wallLines();
  const Eigen::Vector3d cam(0.0, 0.0, 0.5);
  constexpr double kSigmaLine_rad = 0.1 * kPi / 180.0;
  std::mt19937_64 rng(seed * 7 + 1);
  std::normal_distribution<double> n01(0.0, 1.0);
  Pose2 truth{1.5, 1.2, 0.0}, odom = truth;
  if (prior_map) o.update_map = false;
  FastSlam f(o, seed);
  if (prior_map) {
    std::vector<Landmark> map;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      Landmark L;
      L.id = i + 1;
      L.p_LinW_m = lines[i];
      L.cov_LinW_m2 = Eigen::Matrix3d::Identity() * 1e-4;
      L.kind = LandmarkKind::kVerticalLine;
      L.counter = 5;
      map.push_back(L);
    }
    f.initialise(truth, map);
  } else {
    f.initialise(truth);
  }
  LineRun r;
  for (int k = 0; k <= 70; ++k) {
    const Pose2 prev = odom;
    if (k > 0) {
      truth = truth.compose(Pose2{0.1, 0.0, 0.0});
      const double s = odometry_noise ? 1.0 : 0.0;
      odom = odom.compose(Pose2{0.1 + s * 0.03 * std::sqrt(0.1) * n01(rng), 0.0, s * 0.02 * std::sqrt(0.1) * n01(rng)});
    }
    std::vector<BearingMeasurement> z;
    for (const auto& l : lines) {
      const double range = std::hypot(l.x() - truth.x_m, l.y() - truth.y_m);
      if (range < 0.3 || range > 6.0) continue;
      const auto zt = predictMeasurement(LandmarkKind::kVerticalLine, l, truth, cam);
      BearingMeasurement b;
      b.kind = LandmarkKind::kVerticalLine;
      b.p_CinR_m = cam;
      b.azimuth_rad = wrapAngle((*zt)(0) + kSigmaLine_rad * n01(rng));
      b.cov_rad2 = Eigen::Matrix2d::Identity() * kSigmaLine_rad * kSigmaLine_rad;
      z.push_back(b);
    }
    f.step(prev, odom, z);
    const Pose2 m = f.meanPose();
    r.max_theta_err_deg = std::max(r.max_theta_err_deg, std::abs(wrapAngle(m.theta_rad - truth.theta_rad)) * 180.0 / kPi);
  }
  const Pose2 m = f.meanPose();
  r.final_pos_err_m = std::hypot(m.x_m - truth.x_m, m.y_m - truth.y_m);
  r.final_theta_err_deg = wrapAngle(m.theta_rad - truth.theta_rad) * 180.0 / kPi;
  r.num_landmarks = f.bestMap().size();
  return r;
}

// With the true map, the FastSLAM 2.0 proposal holds azimuth-only lines to the truth: the line
// model, its Jacobians and the proposal are sound; the mapping failures come from elsewhere.
TEST(slam_Scenario, LinesFastSlam2LocalisesInTheTrueMap) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const LineRun r = runLines(roomLineOptions(), seed, true, true);
    // 28 lines at 0.1 deg: the heading is held to a fraction of a degree over 7 m (measured: final
    // position <= 0.002 m, largest heading error 0.25 deg), where dead reckoning drifts by 1.5 deg.
    EXPECT_LT(r.final_pos_err_m, 0.02) << "seed " << seed;
    EXPECT_LT(r.max_theta_err_deg, 0.5) << "seed " << seed;
  }
}

// The figures of docs/slam-core.md, "Known limit": final heading error of mapping runs, FastSLAM 2.0
// and 1.0 (ML), with and without candidates.ray_motion_noise, exact and noisy odometry. Run with
//   core_test_slam_scenario --gtest_also_run_disabled_tests --gtest_filter='*LinesSweep*'
TEST(slam_Scenario, DISABLED_LinesSweep) {
  for (int method = 0; method < 2; ++method) {  // FS2 + Hungarian, FS1 + ML
    for (int ray = 0; ray < 2; ++ray) {
      for (int noisy = 0; noisy < 2; ++noisy) {
        FastSlamOptions o = roomLineOptions();
        o.proposal = method > 0 ? ProposalKind::kFastSlam1 : ProposalKind::kFastSlam2;
        o.association = method == 1 ? AssociationMethod::kMaximumLikelihood : AssociationMethod::kHungarian;
        o.candidates.ray_motion_noise = ray != 0;
        std::cout << (method ? "FastSLAM 1.0 + ML" : "FastSLAM 2.0 + Hungarian")
                  << ", ray_motion_noise " << ray
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
