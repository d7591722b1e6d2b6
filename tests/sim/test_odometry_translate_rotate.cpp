// Paper 002's translate-then-rotate odometry noise (OdometryModel::kTranslateRotate) against its
// closed form over many seeds: after a straight of L in n steps the along-track error has std
// err_tran sqrt(L), the heading error err_drift sqrt(L) and the cross-track error
// err_drift sqrt(rho^3 sum_{k<n} k^2) (rho = L / n); after a turn on the spot by phi the heading error
// has std err_rot sqrt(phi) and the position does not move; all means are zero. Also: the default
// (wheel) model still produces exactly the sports hall's former odometry, and the world file
// selects the model and rejects bad values naming the key.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "omnislam/config/world_config.h"
#include "omnislam/sim/odometry_sim.h"

using namespace omnislam;

namespace {

struct Stats {
  double mean = 0.0, std = 0.0, se_mean = 0.0;
};
Stats stats(const std::vector<double>& v) {
  Stats s;
  for (double x : v) s.mean += x;
  s.mean /= static_cast<double>(v.size());
  for (double x : v) s.std += (x - s.mean) * (x - s.mean);
  s.std = std::sqrt(s.std / static_cast<double>(v.size() - 1));
  s.se_mean = s.std / std::sqrt(static_cast<double>(v.size()));
  return s;
}

sim::OdometryNoise trNoise() {
  sim::OdometryNoise nz;
  nz.model = sim::OdometryModel::kTranslateRotate;
  nz.err_tran_m_per_sqrt_m = 0.03;
  nz.err_rot_rad_per_sqrt_rad = 0.05;
  nz.err_drift_rad_per_sqrt_m = 0.02;
  return nz;
}

constexpr int kRuns = 4000;  // std of a sampled std: 1 / sqrt(2 kRuns) = 1.1 %

}  // namespace

TEST(OdometryTranslateRotate, StraightLineErrorsMatchTheClosedForm) {
  const sim::OdometryNoise nz = trNoise();
  const double L = 3.0;
  const int n = 300;  // 1 cm steps
  const double rho = L / n;
  std::vector<double> ex, ey, eth;
  for (int run = 0; run < kRuns; ++run) {
    sim::OdometrySimulator odo(nz, 1000 + static_cast<uint64_t>(run));
    Pose2 p;
    for (int i = 0; i <= n; ++i) p = odo.step(Pose2{i * rho, 0.0, 0.0});
    ex.push_back(p.x_m - L);
    ey.push_back(p.y_m);
    eth.push_back(p.theta_rad);
  }
  double k2 = 0.0;
  for (int k = 1; k < n; ++k) k2 += static_cast<double>(k) * k;
  const double want_x = nz.err_tran_m_per_sqrt_m * std::sqrt(L);
  const double want_th = nz.err_drift_rad_per_sqrt_m * std::sqrt(L);
  const double want_y = nz.err_drift_rad_per_sqrt_m * std::sqrt(rho * rho * rho * k2);
  const Stats sx = stats(ex), sy = stats(ey), sth = stats(eth);
  std::cout << "straight " << L << " m: along-track std " << sx.std << " (model " << want_x << "), cross-track std "
            << sy.std << " (model " << want_y << "), heading std " << sth.std << " (model " << want_th << ")"
            << std::endl;
  EXPECT_NEAR(sx.std / want_x, 1.0, 0.05);
  EXPECT_NEAR(sy.std / want_y, 1.0, 0.05);
  EXPECT_NEAR(sth.std / want_th, 1.0, 0.05);
  // Zero means (the along-track mean has a second-order bias -err_drift^2 L^2 / 4 = 0.4 mm, below
  // one standard error here).
  EXPECT_LT(std::abs(sx.mean), 4.0 * sx.se_mean);
  EXPECT_LT(std::abs(sy.mean), 4.0 * sy.se_mean);
  EXPECT_LT(std::abs(sth.mean), 4.0 * sth.se_mean);
}

TEST(OdometryTranslateRotate, TurnOnTheSpotErrorMatchesTheClosedForm) {
  const sim::OdometryNoise nz = trNoise();
  const double phi = kPi / 2.0;
  const int n = 200;
  std::vector<double> eth;
  for (int run = 0; run < kRuns; ++run) {
    sim::OdometrySimulator odo(nz, 7000 + static_cast<uint64_t>(run));
    Pose2 p;
    for (int i = 0; i <= n; ++i) p = odo.step(Pose2{0.0, 0.0, phi * i / n});
    ASSERT_EQ(p.x_m, 0.0);
    ASSERT_EQ(p.y_m, 0.0);
    eth.push_back(p.theta_rad - phi);
  }
  const Stats s = stats(eth);
  const double want = nz.err_rot_rad_per_sqrt_rad * std::sqrt(phi);
  std::cout << "turn " << phi << " rad: heading std " << s.std << " (model " << want << ")" << std::endl;
  EXPECT_NEAR(s.std / want, 1.0, 0.05);
  EXPECT_LT(std::abs(s.mean), 4.0 * s.se_mean);
}

TEST(OdometryTranslateRotate, NoNoiseIsExactOnArcs) {
  sim::OdometryNoise nz = trNoise();
  nz.err_tran_m_per_sqrt_m = nz.err_rot_rad_per_sqrt_rad = nz.err_drift_rad_per_sqrt_m = 0.0;
  sim::OdometrySimulator odo(nz, 3);
  Pose2 p;
  const double R = 0.5;
  for (int i = 0; i <= 100; ++i) {
    const double a = 1.5 * i / 100.0;
    p = odo.step(Pose2{R * std::sin(a), R * (1.0 - std::cos(a)), a});
  }
  EXPECT_NEAR(p.x_m, R * std::sin(1.5), 1e-12);
  EXPECT_NEAR(p.y_m, R * (1.0 - std::cos(1.5)), 1e-12);
  EXPECT_NEAR(p.theta_rad, 1.5, 1e-12);
}

// The wheel model (default) is the former code path: recompute its formula here and compare bit
// for bit along the sports hall's noise settings.
TEST(OdometryTranslateRotate, WheelModelIsUnchanged) {
  const sim::World hall = config::loadWorld(std::string(OMNISLAM_SOURCE_DIR) + "/config/worlds/sports_hall.yaml");
  const sim::OdometryNoise nz = hall.odometry_noise;
  ASSERT_EQ(nz.model, sim::OdometryModel::kWheel);
  sim::OdometrySimulator odo(nz, 5);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n01(0.0, 1.0);
  const double k_scale = nz.scale_error_sigma * n01(rng);
  const double drift = nz.heading_drift_sigma_rad_per_m * n01(rng);
  Pose2 ref, last;
  for (int i = 0; i <= 500; ++i) {
    const Pose2 truth{0.01 * i, 0.2 * std::sin(0.01 * i), 0.3 * std::sin(0.02 * i)};
    const Pose2 got = odo.step(truth);
    if (i > 0) {
      const Pose2 d = last.between(truth);
      const double dist = std::hypot(d.x_m, d.y_m), ds = d.x_m >= 0.0 ? dist : -dist;
      const double sd = nz.distance_sigma_m_per_sqrt_m * std::sqrt(dist);
      const double sr =
          std::sqrt(nz.rotation_sigma_rad_per_sqrt_rad * nz.rotation_sigma_rad_per_sqrt_rad * std::abs(d.theta_rad) +
                    nz.heading_sigma_rad_per_sqrt_m * nz.heading_sigma_rad_per_sqrt_m * dist);
      const double ds_odo = ds * (1.0 + k_scale) + sd * n01(rng);
      const double dth_odo = d.theta_rad + drift * dist + sr * n01(rng);
      ref = ref.compose(Pose2{ds_odo * std::cos(0.5 * dth_odo), ds_odo * std::sin(0.5 * dth_odo), dth_odo});
    }
    last = truth;
    ASSERT_EQ(got.x_m, ref.x_m) << i;
    ASSERT_EQ(got.y_m, ref.y_m) << i;
    ASSERT_EQ(got.theta_rad, ref.theta_rad) << i;
  }
}

TEST(OdometryTranslateRotate, WorldFileSelectsTheModelAndChecksItsKeys) {
  const sim::World room = config::loadWorld(std::string(OMNISLAM_SOURCE_DIR) + "/config/worlds/room.yaml");
  EXPECT_EQ(room.odometry_noise.model, sim::OdometryModel::kTranslateRotate);
  EXPECT_DOUBLE_EQ(room.odometry_noise.err_tran_m_per_sqrt_m, 0.03);
  const std::string base = R"(
lights: {height_m: 6.5, grid: {x_m: [1.0], y_m: [1.0]}}
camera: {name: fisheye}
trajectory: {start: {x_m: 0, y_m: 0}, segments: [{straight_m: 1.0}]}
)";
  auto load = [&](const std::string& odo) {
    return config::parseWorld(config::Node::loadString(base + odo, "test.yaml"));
  };
  EXPECT_EQ(load("").odometry_noise.model, sim::OdometryModel::kWheel);
  EXPECT_EQ(load("odometry_noise: {model: translate_rotate, err_rot_rad_per_sqrt_rad: 0.1}\n").odometry_noise.model,
            sim::OdometryModel::kTranslateRotate);
  auto fails = [&](const std::string& odo, const std::string& key) {
    try {
      load(odo);
      ADD_FAILURE() << "accepted: " << odo;
    } catch (const config::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  };
  fails("odometry_noise: {model: translate_rotate, err_tran_m_per_sqrt_m: 1.5}\n",
        "odometry_noise.err_tran_m_per_sqrt_m");
  fails("odometry_noise: {model: translate_rotate, err_drift_rad_per_sqrt_m: -0.1}\n",
        "odometry_noise.err_drift_rad_per_sqrt_m");
  fails("odometry_noise: {model: translate_rotate, scale_error_sigma: 0.01}\n", "scale_error_sigma");
  fails("odometry_noise: {model: rotate_translate}\n", "odometry_noise.model");
  fails("odometry_noise: {err_rot_rad_per_sqrt_rad: 0.1}\n", "err_rot_rad_per_sqrt_rad");
}
