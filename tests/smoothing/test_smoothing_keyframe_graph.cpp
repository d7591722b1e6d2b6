// Where the keyframe graph evaluates the odometry's covariance (keyframe_graph.h, OdometryCovarianceAt):
// with a random-walk distance noise, weights taken from each step's measured length bias the map's
// scale down by about the per-step relative variance sigma^2 / d; taken from the keyframes' estimates
// with the length averaged over a window, the scale is unbiased. And adoptSolution: the next build
// starts from the applied solution and moves the keyframes added since by the correction.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <random>
#include <vector>

#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/motion_model.h"
#include "omnislam/smoothing/keyframe_graph.h"

namespace {

using namespace omnislam;
using namespace omnislam::slam;
using namespace omnislam::smoothing;

constexpr double kStepM = 0.2;           // keyframe spacing: the 1 Hz keyframes of a slow robot
constexpr double kWalkSigma = 0.05;      // distance random walk [m / sqrt(m)]
constexpr double kBearingSigma = 0.005;  // azimuth and elevation [rad]

/// Two laps of a 12 x 8 m rectangle, a keyframe every kStepM, anticlockwise from the origin.
std::vector<Pose2> path() {
  std::vector<Pose2> p;
  for (int lap = 0; lap < 2; ++lap) {
    for (double s = 0; s < 12.0 - 1e-9; s += kStepM) p.push_back({s, 0.0, 0.0});
    for (double s = 0; s < 8.0 - 1e-9; s += kStepM) p.push_back({12.0, s, kPi / 2});
    for (double s = 0; s < 12.0 - 1e-9; s += kStepM) p.push_back({12.0 - s, 8.0, kPi});
    for (double s = 0; s < 8.0 - 1e-9; s += kStepM) p.push_back({0.0, 8.0 - s, -kPi / 2});
  }
  p.push_back({0.0, 0.0, 0.0});
  return p;
}

MotionNoiseOptions motion() {
  MotionNoiseOptions m;
  m.model = MotionNoiseModel::kChord;
  m.trans_sigma_per_sqrt_m = kWalkSigma;
  m.min_sigma_xy_m = 0.002;
  m.min_sigma_theta_rad = 0.002;
  return m;
}

/// Records of a run: odometry whose noise is drawn at the true increment (the wheels do not know
/// what was measured), true association to a 4 x 3 grid of lights at 6.5 m, and "filter" estimates
/// that are the truth with independent noise (2 cm, 0.2 deg).
std::vector<KeyframeRecord> records(unsigned seed, std::vector<Landmark>& lights) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  const Eigen::Vector3d p_CinR(0.0, 0.0, 1.8);  // on the axis: the scale comes from the odometry alone
  lights.clear();
  for (int ix = 0; ix < 4; ++ix)
    for (int iy = 0; iy < 3; ++iy) {
      Landmark l;
      l.id = static_cast<std::uint64_t>(100 + lights.size());
      l.p_LinW_m = Eigen::Vector3d(-1.0 + 4.5 * ix, -1.0 + 5.0 * iy, 6.5);
      lights.push_back(l);
    }
  const std::vector<Pose2> truth = path();
  std::vector<KeyframeRecord> out;
  Pose2 odom = truth.front();
  for (std::size_t k = 0; k < truth.size(); ++k) {
    if (k > 0) {
      const Pose2 u = truth[k - 1].between(truth[k]);
      const Eigen::Matrix3d S = incrementCovariance(u, motion());
      const Eigen::Vector3d d = S.llt().matrixL() * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
      odom = odom.compose(Pose2::fromVec(u.vec() + d));
    }
    KeyframeRecord r;
    r.utime = static_cast<std::int64_t>(k) * 1000000;
    r.odom_O = odom;
    r.T_WtoR_filter = {truth[k].x_m + 0.02 * n01(rng), truth[k].y_m + 0.02 * n01(rng),
                       truth[k].theta_rad + 0.0035 * n01(rng)};
    for (const auto& l : lights) {
      const auto zt = predictBearing(l.p_LinW_m, truth[k], p_CinR);
      if (!zt) continue;
      BearingMeasurement z;
      z.p_CinR_m = p_CinR;
      z.cov_rad2 = Eigen::Matrix2d::Identity() * kBearingSigma * kBearingSigma;
      z.azimuth_rad = wrapAngle(zt->x() + kBearingSigma * n01(rng));
      z.elevation_rad = zt->y() + kBearingSigma * n01(rng);
      r.z.push_back(z);
      r.landmark_of_measurement.push_back(static_cast<std::int64_t>(l.id));
    }
    out.push_back(r);
  }
  return out;
}

/// The least-squares scale of the solved positions about the start against the truth.
double solvedScale(const std::vector<KeyframeRecord>& recs, const std::vector<Landmark>& lights,
                   OdometryCovarianceAt at) {
  GraphOptions go;
  go.motion = motion();
  go.start = path().front();
  go.odometry_covariance_at = at;
  KeyframeGraph kg(go);
  for (const auto& r : recs) kg.add(r);
  const Solution s = solve(kg.build(lights));
  EXPECT_TRUE(s.ok) << s.failure;
  const std::vector<Pose2> truth = path();
  double st = 0.0, tt = 0.0;
  for (std::size_t k = 0; k < truth.size() && s.ok; ++k) {
    const Eigen::Vector2d t(truth[k].x_m, truth[k].y_m), e(s.keyframe_poses[k].x_m, s.keyframe_poses[k].y_m);
    st += e.dot(t);
    tt += t.squaredNorm();
  }
  return st / tt;
}

TEST(smoothing_KeyframeGraph, OdometryCovarianceAtTheMeasurementShrinksTheMapAtTheEstimateItDoesNot) {
  constexpr int kSeeds = 10;
  double sum_measured = 0.0, sum_estimate = 0.0, sq_estimate = 0.0;
  for (unsigned seed = 1; seed <= kSeeds; ++seed) {
    std::vector<Landmark> lights;
    const auto recs = records(seed, lights);
    const double m = solvedScale(recs, lights, OdometryCovarianceAt::kMeasured);
    const double e = solvedScale(recs, lights, OdometryCovarianceAt::kEstimate);
    sum_measured += m;
    sum_estimate += e;
    sq_estimate += e * e;
  }
  const double mean_m = sum_measured / kSeeds, mean_e = sum_estimate / kSeeds;
  const double sd_e = std::sqrt(std::max(0.0, sq_estimate / kSeeds - mean_e * mean_e));
  const double bias = kWalkSigma * kWalkSigma / kStepM;  // the relative variance of one step: 1.25 %
  std::cout << "scale over " << kSeeds << " seeds: measured " << mean_m << ", estimate " << mean_e << " (sd " << sd_e
            << "); predicted bias of the measured weights -" << bias << "\n";
  EXPECT_LT(mean_m, 1.0 - 0.5 * bias) << "the measured weights' bias is what this test is about";
  EXPECT_LT(std::abs(mean_e - 1.0), 3.0 * sd_e / std::sqrt(double(kSeeds)) + 1e-4);
  EXPECT_LT(std::abs(mean_e - 1.0), 0.25 * std::abs(mean_m - 1.0));
}

TEST(smoothing_KeyframeGraph, AnAdoptedSolutionIsTheNextStartAndLaterKeyframesMoveWithTheCorrection) {
  std::vector<Landmark> lights;
  auto recs = records(3, lights);
  GraphOptions go;
  go.motion = motion();
  go.start = path().front();
  KeyframeGraph kg(go);
  for (std::size_t k = 0; k + 5 < recs.size(); ++k) kg.add(recs[k]);
  const Graph g1 = kg.build(lights);
  const Solution s = solve(g1);
  ASSERT_TRUE(s.ok) << s.failure;
  for (std::size_t k = recs.size() - 5; k < recs.size(); ++k) kg.add(recs[k]);  // added while it solved
  const Pose2 T_corr{0.3, -0.2, 0.05};
  kg.adoptSolution(s.keyframe_poses, T_corr);
  const Graph g2 = kg.build(lights);
  ASSERT_EQ(g2.keyframes.size(), recs.size());
  for (std::size_t k = 0; k < s.keyframe_poses.size(); ++k)
    EXPECT_EQ(g2.keyframes[k].T_WtoR.vec(), s.keyframe_poses[k].vec()) << k;
  for (std::size_t k = s.keyframe_poses.size(); k < recs.size(); ++k)
    EXPECT_LT((g2.keyframes[k].T_WtoR.vec() - T_corr.compose(recs[k].T_WtoR_filter).vec()).norm(), 1e-12) << k;
  // The odometry itself is what was measured, wherever its covariance is evaluated.
  for (std::size_t i = 0; i < g2.odometry.size(); ++i)
    EXPECT_EQ(g2.odometry[i].u_AtoB.vec(),
              g1.odometry.size() > i ? g1.odometry[i].u_AtoB.vec() : g2.odometry[i].u_AtoB.vec());
}

}  // namespace
