// Global localisation in a saved map (global_localisation.h): the closed forms, an irregular map from
// random start poses, regular grids (ambiguous with the symmetric count, then localised once a
// missing lamp is seen), a map of another building, noise, misses and clutter, determinism.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/global_localisation.h"
#include "slam_scenarios.h"

namespace omnislam::slam {
namespace {

const Eigen::Vector3d kCamInR(0.1, 0.0, 0.5);
constexpr double kSigma_rad = 0.3 * kPi / 180.0;

struct Sensor {
  double range_m = 10.0;  // horizontal range within which lamps are detected
  double p_detect = 1.0;  // detection probability
  double clutter_per_frame = 0.0;
  double sigma_rad = kSigma_rad;
};

std::vector<BearingMeasurement> observe(const std::vector<Eigen::Vector3d>& lamps, const Pose2& truth, const Sensor& s,
                                        std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, s.sigma_rad);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<BearingMeasurement> z;
  const Eigen::Vector2d c = cameraCentreInWorld(truth, kCamInR).head<2>();
  for (const Eigen::Vector3d& p : lamps) {
    if ((p.head<2>() - c).norm() > s.range_m) continue;
    const double draw = u(rng), na = n(rng), ne = n(rng);
    if (draw > s.p_detect) continue;
    const auto b = predictBearing(p, truth, kCamInR);
    if (!b) continue;
    BearingMeasurement m;
    m.azimuth_rad = wrapAngle(b->x() + na), m.elevation_rad = b->y() + ne;
    m.cov_rad2 = Eigen::Matrix2d::Identity() * s.sigma_rad * s.sigma_rad;
    m.p_CinR_m = kCamInR;
    z.push_back(m);
  }
  std::poisson_distribution<int> clutter(s.clutter_per_frame > 0 ? s.clutter_per_frame : 1e-9);
  for (int k = clutter(rng); k > 0; --k) {
    BearingMeasurement m;
    m.azimuth_rad = wrapAngle(2.0 * kPi * u(rng)), m.elevation_rad = 0.2 + 1.3 * u(rng);
    m.cov_rad2 = Eigen::Matrix2d::Identity() * s.sigma_rad * s.sigma_rad;
    m.p_CinR_m = kCamInR;
    z.push_back(m);
  }
  return z;
}

std::vector<Landmark> asMap(const std::vector<Eigen::Vector3d>& lamps, double sigma_m = 0.02) {
  std::vector<Landmark> map;
  for (std::size_t i = 0; i < lamps.size(); ++i) {
    Landmark l;
    l.id = i, l.p_LinW_m = lamps[i], l.cov_LinW_m2 = Eigen::Matrix3d::Identity() * sigma_m * sigma_m;
    map.push_back(l);
  }
  return map;
}

// Lamps at two heights (5.5 m, 6.5 m, +-2 cm) uniformly over [0, w] x [0, h].
std::vector<Eigen::Vector3d> irregularLamps(int n, double w, double h, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3d> l;
  for (int i = 0; i < n; ++i) {
    const double x = w * u(rng), y = h * u(rng), z = (u(rng) < 0.5 ? 5.5 : 6.5) + 0.04 * (u(rng) - 0.5);
    l.emplace_back(x, y, z);
  }
  return l;
}

// Lamps at (spacing i, spacing j), i, j in [0, n), at 6.5 m; `skip` (i, j) left out when given.
std::vector<Eigen::Vector3d> gridLamps(int nx, int ny, double spacing, int skip_i = -1, int skip_j = -1) {
  std::vector<Eigen::Vector3d> l;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      if (i != skip_i || j != skip_j) l.emplace_back(spacing * i, spacing * j, 6.5);
  return l;
}

GlobalLocalisationOptions optionsFor(const Sensor& s) {
  GlobalLocalisationOptions o;
  o.max_range_m = s.range_m;
  o.clutter_per_frame = std::max(s.clutter_per_frame, 0.1);
  return o;
}

PerceptionOptions perceptionFor(const Sensor& s) {
  PerceptionOptions p;
  p.detection_probability = std::min(std::max(s.p_detect, 0.5), 0.95);
  p.default_p_CinR_m = kCamInR;
  return p;
}

double headingError_deg(const Pose2& a, const Pose2& b) {
  return std::abs(rad2deg(wrapAngle(a.theta_rad - b.theta_rad)));
}
double positionError_m(const Pose2& a, const Pose2& b) { return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m); }

// A drive: `frames` steps of `step_m` turning `turn_deg` per step from `start`; the odometry has a 2 %
// scale error and 0.2 deg of heading noise per step. Calls check(frame, truth, status) after each.
template <class Check>
void drive(GlobalLocaliser& loc, const std::vector<Eigen::Vector3d>& lamps, const Sensor& s, Pose2 truth, int frames,
           double step_m, double turn_deg, std::uint64_t seed, Check check) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  Pose2 odom{0.0, 0.0, 0.0}, odom_prev = odom;
  for (int k = 0; k < frames; ++k) {
    const LocalisationStatus& st = loc.step(odom_prev, odom, observe(lamps, truth, s, rng));
    check(k, truth, st);
    const Pose2 u{step_m, 0.0, deg2rad(turn_deg)};
    truth = truth.compose(u);
    odom_prev = odom;
    odom = odom.compose(Pose2{1.02 * step_m, 0.0, u.theta_rad + deg2rad(0.2) * n(rng)});
  }
}

TEST(slam_GlobalLocalisation, PoseFromTwoLampsInvertsARigidMotion) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  for (int t = 0; t < 100; ++t) {
    const Pose2 T{u(rng), u(rng), wrapAngle(u(rng))};
    const Eigen::Vector2d a_R(u(rng), u(rng)), b_R(u(rng), u(rng));
    const auto p = poseFromTwoLamps(a_R, b_R, T.transformFrom(a_R), T.transformFrom(b_R));
    ASSERT_TRUE(p.has_value());
    EXPECT_NEAR(p->x_m, T.x_m, 1e-9);
    EXPECT_NEAR(p->y_m, T.y_m, 1e-9);
    EXPECT_NEAR(wrapAngle(p->theta_rad - T.theta_rad), 0.0, 1e-12);
  }
  // A quarter turn about the origin by hand: (1, 0) -> (0, 1), (2, 0) -> (0, 2).
  const auto q = poseFromTwoLamps({1, 0}, {2, 0}, {0, 1}, {0, 2});
  ASSERT_TRUE(q.has_value());
  EXPECT_NEAR(q->x_m, 0.0, 1e-12);
  EXPECT_NEAR(q->y_m, 0.0, 1e-12);
  EXPECT_NEAR(q->theta_rad, kPi / 2, 1e-12);
  EXPECT_FALSE(poseFromTwoLamps({1, 1}, {1, 1}, {0, 0}, {1, 0}).has_value());
  EXPECT_FALSE(poseFromTwoLamps({1, 1}, {2, 1}, {3, 3}, {3, 3}).has_value());
}

TEST(slam_GlobalLocalisation, HorizontalPointInvertsTheBearingModel) {
  const Eigen::Vector3d lamp(4.0, -3.0, 6.5);
  const auto b = predictBearing(lamp, Pose2{}, kCamInR);
  ASSERT_TRUE(b.has_value());
  const auto q = horizontalPointInRobot(b->x(), b->y(), kCamInR, 6.5, 100.0);
  ASSERT_TRUE(q.has_value());
  EXPECT_NEAR(q->x(), 4.0, 1e-12);
  EXPECT_NEAR(q->y(), -3.0, 1e-12);
  EXPECT_FALSE(horizontalPointInRobot(b->x(), b->y(), kCamInR, 6.5, 4.0).has_value());     // beyond the range
  EXPECT_FALSE(horizontalPointInRobot(b->x(), -b->y(), kCamInR, 6.5, 100.0).has_value());  // points down
  EXPECT_FALSE(horizontalPointInRobot(b->x(), 0.0, kCamInR, 6.5, 100.0).has_value());      // horizontal
}

TEST(slam_GlobalLocalisation, OptionsValidateNamesTheKey) {
  EXPECT_EQ(GlobalLocalisationOptions{}.validate(), "");
  GlobalLocalisationOptions o;
  o.gate_probability = 1.5;
  EXPECT_NE(o.validate().find("gate_probability"), std::string::npos) << o.validate();
  o = {};
  o.min_matched = 10, o.max_seed_bearings = 5;
  EXPECT_NE(o.validate().find("min_matched"), std::string::npos) << o.validate();
  o = {};
  o.drop_likelihood_ratio = 10.0;
  EXPECT_NE(o.validate().find("drop_likelihood_ratio"), std::string::npos) << o.validate();
  EXPECT_THROW(GlobalLocaliser(o, MotionNoiseOptions{}, PerceptionOptions{}, {}), std::invalid_argument);
}

TEST(slam_GlobalLocalisation, IrregularMapRandomStartsAreLocalisedCorrectly) {
  const std::vector<Eigen::Vector3d> lamps = irregularLamps(90, 40.0, 40.0, 11);
  Sensor s;
  s.p_detect = 0.9, s.clutter_per_frame = 1.0;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int run = 0; run < 20; ++run) {
    const Pose2 start{8.0 + 24.0 * u(rng), 8.0 + 24.0 * u(rng), wrapAngle(2.0 * kPi * u(rng))};
    GlobalLocaliser loc(optionsFor(s), MotionNoiseOptions{}, perceptionFor(s), asMap(lamps));
    int first_fix = -1;
    // 20 frames of 0.25 m: at most 5 m of travel.
    drive(loc, lamps, s, start, 20, 0.25, 4.0, 100 + run, [&](int k, const Pose2& truth, const LocalisationStatus& st) {
      if (st.state != LocalisationState::kLocalised) return;
      if (first_fix < 0) first_fix = k;
      EXPECT_LT(positionError_m(st.best.at(0).pose_W, truth), 0.3) << "run " << run << " frame " << k;
      EXPECT_LT(headingError_deg(st.best.at(0).pose_W, truth), 2.0) << "run " << run << " frame " << k;
    });
    EXPECT_GE(first_fix, 0) << "run " << run << ": never localised";
  }
}

// Every proper rigid motion g of the square lattice (a quarter turn about a centre of symmetry, then a
// lattice translation) under which the lamps within range of g(truth) are, seen from it, those seen
// from the truth: the hypotheses a regular grid cannot tell apart.
int symmetricPoses(const std::vector<Eigen::Vector3d>& lamps, const Pose2& truth, double range_m,
                   const Eigen::Vector2d& centre, double spacing) {
  auto seen = [&](const Pose2& p) {
    std::vector<Eigen::Vector2d> v;
    const Eigen::Vector2d c = cameraCentreInWorld(p, kCamInR).head<2>();
    const Pose2 inv = p.inverse();
    for (const auto& l : lamps)
      if ((l.head<2>() - c).norm() <= range_m) v.push_back(inv.transformFrom(l.head<2>()));
    return v;
  };
  const auto ref = seen(truth);
  int count = 0;
  for (int k = 0; k < 4; ++k)
    for (int a = -10; a <= 10; ++a)
      for (int b = -10; b <= 10; ++b) {
        const Pose2 g = Pose2{centre.x() + spacing * a, centre.y() + spacing * b, 0.0}
                            .compose(Pose2{0.0, 0.0, k * kPi / 2})
                            .compose(Pose2{-centre.x(), -centre.y(), 0.0});
        const auto v = seen(g.compose(truth));
        bool same = v.size() == ref.size();
        for (const auto& p : ref) {
          bool found = false;
          for (const auto& q : v) found = found || (p - q).norm() < 1e-6;
          same = same && found;
        }
        count += same ? 1 : 0;
      }
  return count;
}

TEST(slam_GlobalLocalisation, RegularGridIsAmbiguousWithItsSymmetricCount) {
  // 8 x 8 lamps 4 m apart; 7 m of range from the middle of a cell sees a 4 x 4 block without corners.
  const std::vector<Eigen::Vector3d> lamps = gridLamps(8, 8, 4.0);
  Sensor s;
  s.range_m = 7.0;
  const Pose2 truth = Pose2{14.0, 14.0, 0.3}.compose(Pose2{-kCamInR.x(), 0.0, 0.0});
  const int expected = symmetricPoses(lamps, truth, s.range_m, {14.0, 14.0}, 4.0);
  EXPECT_EQ(expected, 100);  // 5 x 5 places of the block, 4 headings
  GlobalLocaliser loc(optionsFor(s), MotionNoiseOptions{}, perceptionFor(s), asMap(lamps));
  drive(loc, lamps, s, truth, 6, 0.0, 0.0, 5, [&](int k, const Pose2&, const LocalisationStatus& st) {
    EXPECT_NE(st.state, LocalisationState::kLocalised) << "frame " << k;
    if (k > 0) {
      EXPECT_EQ(st.state, LocalisationState::kAmbiguous) << "frame " << k;
      EXPECT_EQ(st.num_hypotheses, expected) << "frame " << k;
    }
  });
}

TEST(slam_GlobalLocalisation, SmallSquareGridStaysAmbiguousWhileDriving) {
  // 3 x 3 lamps 3 m apart, all always in view: the four quarter turns about the centre agree forever.
  const std::vector<Eigen::Vector3d> lamps = gridLamps(3, 3, 3.0);
  Sensor s;
  s.range_m = 30.0;
  s.p_detect = 0.9;
  GlobalLocaliser loc(optionsFor(s), MotionNoiseOptions{}, perceptionFor(s), asMap(lamps));
  drive(loc, lamps, s, Pose2{1.0, 2.0, 0.4}, 30, 0.2, 6.0, 9, [&](int k, const Pose2&, const LocalisationStatus& st) {
    EXPECT_NE(st.state, LocalisationState::kLocalised) << "frame " << k;
    if (k >= 2) {
      EXPECT_EQ(st.num_hypotheses, 4) << "frame " << k;
    }
  });
}

TEST(slam_GlobalLocalisation, GridWithAMissingLampIsLocalisedOnceTheHoleIsSeen) {
  const std::vector<Eigen::Vector3d> lamps = gridLamps(8, 8, 4.0, 6, 3);  // no lamp at (24, 12)
  const Eigen::Vector2d hole(24.0, 12.0);
  Sensor s;
  s.range_m = 7.0;
  s.p_detect = 0.95;
  GlobalLocaliser loc(optionsFor(s), MotionNoiseOptions{}, perceptionFor(s), asMap(lamps));
  bool hole_seen = false;
  int first_fix = -1;
  drive(loc, lamps, s, Pose2{8.0, 10.0, 0.0}, 60, 0.25, 0.0, 21,
        [&](int k, const Pose2& truth, const LocalisationStatus& st) {
          if (st.state == LocalisationState::kLocalised) {
            if (first_fix < 0) first_fix = k;
            EXPECT_TRUE(hole_seen) << "localised at frame " << k << " before the hole was in view";
            EXPECT_LT(positionError_m(st.best.at(0).pose_W, truth), 0.3) << "frame " << k;
            EXPECT_LT(headingError_deg(st.best.at(0).pose_W, truth), 2.0) << "frame " << k;
          }
          hole_seen = hole_seen || (cameraCentreInWorld(truth, kCamInR).head<2>() - hole).norm() <= s.range_m;
        });
  EXPECT_GE(first_fix, 0) << "never localised";
}

// The sports hall of paper 000 (tests/core/slam_scenarios.h): 4 x 4 lights 9 m x 4.5 m apart, the same
// after a half turn about the hall's centre. From every pose of its 86 m loop the half-turned pose sees
// the same lights: it must stay ambiguous (two hypotheses) and never be localised.
TEST(slam_GlobalLocalisation, SportsHallIsHalfTurnSymmetricAndNeverLocalised) {
  std::vector<Landmark> map = asMap(scenarios::hallLights());
  PerceptionOptions p;
  p.default_p_CinR_m = scenarios::kCamInR;
  GlobalLocaliser loc(GlobalLocalisationOptions{}, MotionNoiseOptions{}, p, map);
  const std::vector<scenarios::Frame> frames = scenarios::simulateHall(1);
  int ambiguous_two = 0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const LocalisationStatus& st = loc.step(frames[k > 0 ? k - 1 : 0].odom, frames[k].odom, frames[k].z);
    ASSERT_NE(st.state, LocalisationState::kLocalised) << "frame " << k;
    if (st.state == LocalisationState::kAmbiguous && st.num_hypotheses == 2) ++ambiguous_two;
  }
  EXPECT_GT(ambiguous_two, static_cast<int>(frames.size()) * 9 / 10) << "of " << frames.size() << " frames";
}

// The same with a map whose lamps are off by N(0, 3 cm) each (a real map is never exact): the map's
// errors are the same in every frame, so the two half-turned poses' likelihoods drift apart by how the
// errors fit each. Before the counts' evidence C (global_localisation.h, "Shared map error") the live
// hall was localised at the half-turned pose at frame 7; with C counting a match for a lamp at the
// range's edge for one pose and not its twin, 2 of these 5 draws were localised (frames 77 and 132).
// Now none of these 5 draws of the map's errors is ever localised (of 30 draws, one was: draw 13 at
// frame 96, 26 m; the known weakness in docs/design/global-localisation.md). 5 draws: ~35 s here.
TEST(slam_GlobalLocalisation, SportsHallWithANoisyMapIsStillNeverLocalised) {
  PerceptionOptions p;
  p.default_p_CinR_m = scenarios::kCamInR;
  const std::vector<scenarios::Frame> frames = scenarios::simulateHall(1);
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> n(0.0, 0.03);
    std::vector<Eigen::Vector3d> lamps = scenarios::hallLights();
    for (Eigen::Vector3d& l : lamps) l += Eigen::Vector3d(n(rng), n(rng), n(rng));
    GlobalLocaliser loc(GlobalLocalisationOptions{}, MotionNoiseOptions{}, p, asMap(lamps, 0.03));
    int ambiguous = 0;
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const LocalisationStatus& st = loc.step(frames[k > 0 ? k - 1 : 0].odom, frames[k].odom, frames[k].z);
      ASSERT_NE(st.state, LocalisationState::kLocalised) << "map draw " << seed << ", frame " << k;
      ambiguous += st.state == LocalisationState::kAmbiguous;
    }
    EXPECT_GT(ambiguous, static_cast<int>(frames.size()) * 9 / 10) << "map draw " << seed;
  }
}

// A test's random stream: its engine and the distributions it draws from (kept across frames, so that
// the draws are those of one sequence).
struct Draws {
  std::mt19937_64& rng;
  std::uniform_real_distribution<double>& u;  // [0, 1)
  std::normal_distribution<double>& n;        // N(0, kSigma_rad)
};

// The bearings of the lamps within range_m (3-D) of the camera `cam` at `truth`, each detected with
// p_detect, with n's noise on each angle; three draws per lamp, detected or not.
std::vector<BearingMeasurement> observeWithin3d(const std::vector<Eigen::Vector3d>& lamps, const Pose2& truth,
                                                const Eigen::Vector3d& cam, double range_m, double p_detect, Draws d) {
  std::vector<BearingMeasurement> z;
  const Eigen::Vector3d c = cameraCentreInWorld(truth, cam);
  for (const Eigen::Vector3d& l : lamps) {
    const double draw = d.u(d.rng), na = d.n(d.rng), ne = d.n(d.rng);
    if ((l - c).norm() > range_m || draw > p_detect) continue;
    const auto b = predictBearing(l, truth, cam);
    BearingMeasurement m;
    m.azimuth_rad = wrapAngle(b->x() + na), m.elevation_rad = b->y() + ne, m.p_CinR_m = cam;
    m.cov_rad2 = Eigen::Matrix2d::Identity() * kSigma_rad * kSigma_rad;
    z.push_back(m);
  }
  return z;
}

// Frame k's status: the first localised frame is recorded, and a fix must be within issue 56's
// 0.3 m / 2 deg of the truth.
void checkFix(const LocalisationStatus& st, const Pose2& truth, int k, int& first_fix) {
  if (st.state != LocalisationState::kLocalised) return;
  if (first_fix < 0) first_fix = k;
  EXPECT_LT(positionError_m(st.best.at(0).pose_W, truth), 0.3) << "frame " << k;
  EXPECT_LT(headingError_deg(st.best.at(0).pose_W, truth), 2.0) << "frame " << k;
}

// Generated world halls 28 (docs/design/global-localisation.md, Kidnap): a 5.66 m x 7.54 m grid of lamps
// at 5.55 m with 14 missing and 4 extra, seen by a camera 1.8 m up whose perceptual range (17.36 m in
// 3D) is shorter than the localiser's max_range_m (20 m). The seeds' count test expected every lamp
// within 20 m (21 at this start, 12 inside the range): the true pose, which explains every bearing,
// was refused in every frame, and a pose 4 grid spacings off (16 lamps within 20 m) was localised
// instead, at frame 7 of the log.
std::vector<Eigen::Vector3d> halls28Lamps() {
  const double xy[][2] = {{3.18, 4.35},   {3.18, 11.89},    {3.18, 26.97},    {3.18, 34.51},   {3.18, 42.05},
                          {8.84, 11.89},  {8.84, 19.43},    {8.84, 26.97},    {8.84, 34.51},   {8.84, 42.05},
                          {14.5, 4.35},   {14.5, 11.89},    {14.5, 19.43},    {14.5, 26.97},   {14.5, 34.51},
                          {14.5, 42.05},  {20.16, 11.89},   {20.16, 19.43},   {20.16, 42.05},  {25.82, 4.35},
                          {25.82, 11.89}, {25.82, 19.43},   {25.82, 26.97},   {25.82, 34.51},  {31.48, 11.89},
                          {31.48, 26.97}, {31.48, 34.51},   {31.48, 42.05},   {37.14, 4.35},   {37.14, 11.89},
                          {37.14, 19.43}, {37.14, 26.97},   {37.14, 34.51},   {37.14, 42.05},  {42.8, 11.89},
                          {42.8, 26.97},  {42.8, 34.51},    {42.8, 42.05},    {48.46, 4.35},   {48.46, 19.43},
                          {48.46, 42.05}, {54.12, 4.35},    {54.12, 11.89},   {54.12, 19.43},  {54.12, 34.51},
                          {54.12, 42.05}, {34.761, 26.753}, {49.608, 44.583}, {32.007, 1.073}, {40.394, 25.834}};
  std::vector<Eigen::Vector3d> l;
  for (const auto& p : xy) l.emplace_back(p[0], p[1], 5.55);
  return l;
}

TEST(slam_GlobalLocalisation, PerceptualRangeShorterThanMaxRangeStillSeedsTheTruth) {
  const std::vector<Eigen::Vector3d> lamps = halls28Lamps();
  const Eigen::Vector3d cam(0.0, 0.0, 1.8);
  PerceptionOptions p;
  p.max_range_m = 17.36, p.min_elevation_rad = deg2rad(-5.0), p.detection_probability = 0.9;
  p.default_p_CinR_m = cam;
  std::mt19937_64 rng(28);
  std::normal_distribution<double> n(0.0, kSigma_rad);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  GlobalLocaliser loc(GlobalLocalisationOptions{}, MotionNoiseOptions{}, p, asMap(lamps, 0.03));
  Pose2 truth{33.6, 9.4, deg2rad(154.0)}, odom{}, odom_prev{};
  int first_fix = -1, first_near = -1;
  for (int k = 0; k < 20; ++k) {  // 20 frames of 0.25 m: 5 m
    const LocalisationStatus& st =
        loc.step(odom_prev, odom, observeWithin3d(lamps, truth, cam, p.max_range_m, 0.9, Draws{rng, u, n}));
    for (const PoseHypothesis& h : loc.hypotheses())
      if (first_near < 0 && positionError_m(h.pose_W, truth) < 0.3 && headingError_deg(h.pose_W, truth) < 2.0)
        first_near = k;
    checkFix(st, truth, k, first_fix);
    const Pose2 step{0.25, 0.0, deg2rad(2.0)};
    truth = truth.compose(step), odom_prev = odom, odom = odom.compose(step);
  }
  EXPECT_EQ(first_near, 0) << "the true pose is a hypothesis from the first frame on";
  EXPECT_GE(first_fix, 0) << "never localised";
}

// Lamps at every height from 4 to 7 m (one height class: neighbours closer than height_tolerance_m
// chain) are seeded from two bearings placed at the class's height, 0.5 m and 10 deg off; two rounds of
// assignment and fit matched 3-22 of about 42 lamps and the count test refused the true pose (irregular 44:
// "lost" for 23 frames). The seed's fit is repeated while its matches grow.
TEST(slam_GlobalLocalisation, LampsAtManyHeightsAreLocalisedFromTheFirstFrames) {
  std::mt19937_64 gen(44);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3d> lamps;
  for (int i = 0; i < 110; ++i) lamps.emplace_back(53.0 * u(gen), 57.0 * u(gen), 4.0 + 3.0 * u(gen));
  const Eigen::Vector3d cam(0.0, 0.0, 1.8);
  PerceptionOptions p;
  p.max_range_m = 26.8, p.min_elevation_rad = deg2rad(-5.0), p.detection_probability = 0.9;
  p.default_p_CinR_m = cam;
  std::normal_distribution<double> n(0.0, kSigma_rad);
  GlobalLocaliser loc(GlobalLocalisationOptions{}, MotionNoiseOptions{}, p, asMap(lamps, 0.03));
  ASSERT_EQ(loc.index().classHeights().size(), 1u) << "the test's premise: one height class for 4-7 m";
  Pose2 truth{26.0, 28.0, deg2rad(35.0)}, odom{}, odom_prev{};
  int first_fix = -1;
  for (int k = 0; k < 20; ++k) {  // 20 frames of 0.25 m: 5 m
    const LocalisationStatus& st =
        loc.step(odom_prev, odom, observeWithin3d(lamps, truth, cam, p.max_range_m, 0.9, Draws{gen, u, n}));
    EXPECT_NE(st.state, LocalisationState::kLost) << "frame " << k;
    checkFix(st, truth, k, first_fix);
    const Pose2 step{0.25, 0.0, deg2rad(2.0)};
    truth = truth.compose(step), odom_prev = odom, odom = odom.compose(step);
  }
  EXPECT_GE(first_fix, 0) << "never localised";
  EXPECT_LE(first_fix, 2) << "localised only after " << first_fix
                          << " frames (min_frames 3, min_travel_m 0.5: frame 2)";
}

// A hypothesis is confirmed by the frames after its birth, not by those it was run back through: in
// the first 6 frames only the two highest lamps are seen (no seed: fewer than min_matched bearings),
// then every lamp in range. The pose seeded in frame 6 explains the earlier frames run backwards, yet
// it is localised no earlier than min_frames frames and min_travel_m from its birth.
TEST(slam_GlobalLocalisation, ConfirmedOnlyByFramesAfterItsBirth) {
  const std::vector<Eigen::Vector3d> lamps = irregularLamps(90, 40.0, 40.0, 11);
  Sensor s;
  const GlobalLocalisationOptions o = optionsFor(s);
  GlobalLocaliser loc(o, MotionNoiseOptions{}, perceptionFor(s), asMap(lamps));
  std::mt19937_64 rng(5);
  Pose2 truth{20.0, 20.0, 0.5}, odom{}, odom_prev{};
  constexpr int kBirth = 6;
  const double step_m = 0.3;
  int first_fix = -1;
  for (int k = 0; k < 20; ++k) {
    std::vector<BearingMeasurement> z = observe(lamps, truth, s, rng);
    std::sort(z.begin(), z.end(), [](const auto& a, const auto& b) { return a.elevation_rad > b.elevation_rad; });
    if (k < kBirth && z.size() > 2) z.resize(2);
    const LocalisationStatus& st = loc.step(odom_prev, odom, z);
    if (st.state == LocalisationState::kLocalised && first_fix < 0) {
      first_fix = k;
      EXPECT_LT(positionError_m(st.best.at(0).pose_W, truth), 0.3);
      EXPECT_GE(st.best.at(0).frames_explained, o.min_frames);
      EXPECT_GE(st.best.at(0).travel_m, o.min_travel_m);
    }
    const Pose2 u{step_m, 0.0, deg2rad(3.0)};
    truth = truth.compose(u), odom_prev = odom, odom = odom.compose(u);
  }
  ASSERT_GE(first_fix, 0) << "never localised";
  EXPECT_GE(first_fix, kBirth + std::max(o.min_frames - 1, static_cast<int>(std::ceil(o.min_travel_m / step_m))));
}

TEST(slam_GlobalLocalisation, MapOfAnotherBuildingIsNeverLocalised) {
  const std::vector<Eigen::Vector3d> here = irregularLamps(90, 40.0, 40.0, 11);
  const std::vector<Eigen::Vector3d> elsewhere = irregularLamps(90, 40.0, 40.0, 12);
  Sensor s;
  s.p_detect = 0.9, s.clutter_per_frame = 1.0;
  GlobalLocaliser loc(optionsFor(s), MotionNoiseOptions{}, perceptionFor(s), asMap(here));
  LocalisationState last = LocalisationState::kSearching;
  drive(loc, elsewhere, s, Pose2{20.0, 20.0, 1.0}, 30, 0.25, 3.0, 4,
        [&](int k, const Pose2&, const LocalisationStatus& st) {
          EXPECT_NE(st.state, LocalisationState::kLocalised) << "frame " << k;
          last = st.state;
        });
  EXPECT_NE(last, LocalisationState::kLocalised);
}

TEST(slam_GlobalLocalisation, NoFrameOrTooFewBearingsKeepsSearching) {
  const std::vector<Eigen::Vector3d> lamps = irregularLamps(40, 30.0, 30.0, 2);
  Sensor s;
  GlobalLocaliser loc(optionsFor(s), MotionNoiseOptions{}, perceptionFor(s), asMap(lamps));
  EXPECT_EQ(loc.step(Pose2{}, Pose2{}, {}).state, LocalisationState::kSearching);
  BearingMeasurement m;
  m.elevation_rad = 1.0, m.p_CinR_m = kCamInR;
  EXPECT_EQ(loc.step(Pose2{}, Pose2{}, {m, m}).state, LocalisationState::kSearching);
  m.azimuth_rad = std::nan("");
  EXPECT_EQ(loc.step(Pose2{}, Pose2{}, {m}).state, LocalisationState::kSearching);  // non-finite: ignored
}

TEST(slam_GlobalLocalisation, BitForBitDeterministic) {
  const std::vector<Eigen::Vector3d> lamps = irregularLamps(90, 40.0, 40.0, 11);
  Sensor s;
  s.p_detect = 0.9, s.clutter_per_frame = 1.0;
  auto run = [&] {
    GlobalLocaliser loc(optionsFor(s), MotionNoiseOptions{}, perceptionFor(s), asMap(lamps));
    std::vector<double> trace;
    drive(
        loc, lamps, s, Pose2{15.0, 22.0, -2.0}, 15, 0.25, 4.0, 77,
        [&](int, const Pose2&, const LocalisationStatus& st) {
          trace.push_back(static_cast<double>(st.state));
          trace.push_back(st.num_tracked);
          for (const auto& h : loc.hypotheses())
            trace.insert(trace.end(), {h.pose_W.x_m, h.pose_W.y_m, h.pose_W.theta_rad, h.log_likelihood, h.cov(0, 0)});
        });
    return trace;
  };
  const std::vector<double> a = run(), b = run();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "entry " << i;  // exact
}

}  // namespace
}  // namespace omnislam::slam
