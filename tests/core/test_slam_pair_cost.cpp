// Tests of the corrected pair score's linearised prediction (LinearisedPairPrediction,
// filter.association_linearised): its closed form (Woodbury) against Alg. 2 lines 6-11 written out
// with the first-order prediction zbar + H_x dmu; its agreement with the exact score (h evaluated
// again at the corrected pose) to first order in the correction; the same associations on frames
// of a lamp grid; and the option's key.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "omnislam/core/slam/data_association.h"
#include "omnislam/core/slam/filter_stages.h"
#include "omnislam/core/slam/options_table.h"

namespace {

using namespace omnislam;
using namespace omnislam::slam;

const Eigen::Vector3d kCam(0.1, -0.05, 1.8);

// Alg. 2 lines 2-11 for one pair, written out in dynamic-size Eigen with the generic inverses; the
// prediction of line 10 exact (h at mu_x,jl) or to first order (zbar + H_x dmu).
double pairCostByHand(const Landmark& L, const stages::Measurement& m, const stages::MotionPrediction& pred,
                      bool first_order) {
  MeasJac Hx, Hm;
  const MeasVec zbar = *predictMeasurement(L.kind, L.p_LinW_m, pred.x_hat, m.p_CinR_m, &Hx, &Hm);
  const Eigen::MatrixXd Qjl = m.Q + Hm * L.cov_LinW_m2 * Hm.transpose();
  const Eigen::MatrixXd Qinv = Qjl.inverse();
  const Eigen::Matrix3d Sx = (Hx.transpose() * Qinv * Hx + pred.R.inverse()).inverse();
  const MeasVec nu = innovation(m.z, zbar);
  const Eigen::Vector3d dmu = Sx * Hx.transpose() * Qinv * nu;
  MeasVec r = nu - Hx * dmu;
  if (!first_order) {
    const Pose2 mu{pred.x_hat.x_m + dmu(0), pred.x_hat.y_m + dmu(1), wrapAngle(pred.x_hat.theta_rad + dmu(2))};
    r = innovation(m.z, *predictMeasurement(L.kind, L.p_LinW_m, mu, m.p_CinR_m));
  }
  const double dim = static_cast<double>(r.size());
  return 0.5 * (dim * std::log(2.0 * kPi) + std::log(Qjl.determinant()) + r.dot(Qinv * r));
}

struct OnePair {
  std::vector<Landmark> landmarks;
  LandmarkMap map{4.0};
  std::vector<LandmarkMap::Ref> visible;
  std::vector<stages::Measurement> Z;
  stages::MotionPrediction pred;
};

// One landmark of `kind` and one measurement of it: the bearing predicted from xhat offset by
// `offset_rad` (azimuth, and elevation for a point), so nu = offset; xhat after a 0.6 m odometry step.
void makePair(OnePair& p, LandmarkKind kind, const Eigen::Vector2d& offset_rad) {
  Landmark L;
  L.id = 1, L.kind = kind, L.p_LinW_m = Eigen::Vector3d(4.0, 2.5, 5.5), L.type = LandmarkType::kTypeI;
  L.cov_LinW_m2 << 0.004, 0.001, 0.0, 0.001, 0.003, 0.0005, 0.0, 0.0005, 0.002;
  p.map.apply({}, {L});
  p.map.collectAll(p.visible);
  MotionNoiseOptions motion;
  p.pred = stages::predictMotion(Pose2{0.2, -0.1, 0.4}, Pose2{0.6, 0.05, 0.1}, motion);
  const MeasVec z = *predictMeasurement(kind, L.p_LinW_m, p.pred.x_hat, kCam);  // nu = offset_rad
  BearingMeasurement b;
  b.kind = kind, b.p_CinR_m = kCam;
  b.azimuth_rad = wrapAngle(z(0) + offset_rad(0));
  b.elevation_rad = kind == LandmarkKind::kPoint3D ? z(1) + offset_rad(1) : 0.0;
  b.cov_rad2 << 4e-5, 1e-6, 1e-6, 3e-5;
  p.Z = {*stages::prepareMeasurement(b, 0, true, 64.0)};
}

// The closed form of the linearised score is Alg. 2 with line 10 to first order (Woodbury on line
// 7), and the exact score is Alg. 2 as written: both against the generic algebra, for both kinds.
TEST(slam_PairCost, ClosedFormsAreAlg2WrittenOut) {
  for (const LandmarkKind kind : {LandmarkKind::kPoint3D, LandmarkKind::kVerticalLine}) {
    for (const double off : {0.0, 0.01, -0.03, 0.08}) {
      OnePair p;
      makePair(p, kind, Eigen::Vector2d(off, -0.5 * off));
      const Landmark& L = *p.visible[0].landmark;
      const double lin = stages::scorePairsLinearised(p.visible, p.Z, p.pred)(0, 0);
      const double exact = stages::scorePairsCorrected(p.visible, p.Z, p.pred)(0, 0);
      const double lin_ref = pairCostByHand(L, p.Z[0], p.pred, true);
      const double exact_ref = pairCostByHand(L, p.Z[0], p.pred, false);
      ASSERT_TRUE(std::isfinite(lin_ref) && std::isfinite(exact_ref));
      EXPECT_NEAR(lin, lin_ref, 1e-9 * std::max(1.0, std::abs(lin_ref))) << static_cast<int>(kind) << " " << off;
      EXPECT_NEAR(exact, exact_ref, 1e-9 * std::max(1.0, std::abs(exact_ref))) << static_cast<int>(kind) << " " << off;
    }
  }
}

// To first order: z - zhat differs between the two by O(|dmu|^2) while both are O(|dmu|), so the
// costs differ by O(eps^3) when the innovation (and with it the correction) is eps times a fixed
// direction: halving eps divides the difference by about 8. The Mahalanobis parts themselves
// (O(eps^2)) are far larger than the difference.
TEST(slam_PairCost, LinearisedAgreesWithExactToFirstOrder) {
  for (const LandmarkKind kind : {LandmarkKind::kPoint3D, LandmarkKind::kVerticalLine}) {
    std::vector<double> diff, mahalanobis;
    for (const double eps : {0.04, 0.02, 0.01, 0.005}) {
      OnePair p;
      makePair(p, kind, Eigen::Vector2d(eps, 0.7 * eps));
      const double lin = stages::scorePairsLinearised(p.visible, p.Z, p.pred)(0, 0);
      const double exact = stages::scorePairsCorrected(p.visible, p.Z, p.pred)(0, 0);
      OnePair zero;
      makePair(zero, kind, Eigen::Vector2d::Zero());
      diff.push_back(std::abs(exact - lin));
      mahalanobis.push_back(exact - stages::scorePairsCorrected(zero.visible, zero.Z, zero.pred)(0, 0));
    }
    for (std::size_t i = 1; i < diff.size(); ++i) {
      const double ratio = diff[i - 1] / diff[i];
      EXPECT_GT(ratio, 5.0) << static_cast<int>(kind) << " eps step " << i << ": " << diff[i - 1] << " / " << diff[i];
      EXPECT_LT(ratio, 11.0) << static_cast<int>(kind) << " eps step " << i << ": " << diff[i - 1] << " / " << diff[i];
      EXPECT_LT(diff[i], 1e-2 * std::abs(mahalanobis[i])) << static_cast<int>(kind) << " eps step " << i;
    }
  }
}

// A frame of the lamp grid (4.5 m spacing at 6.5 m, a camera at 1.8 m, range 9.5 m, 0.3 deg noise)
// seen from a pose the odometry got wrong by its own noise: the pairs, their costs and the "new"
// costs of each measurement.
struct GridFrame {
  LandmarkMap map{4.0};
  std::vector<LandmarkMap::Ref> visible;
  std::vector<stages::Measurement> Z;
  stages::MotionPrediction pred;
  std::vector<double> cost_new;
};

void makeGridFrame(GridFrame& f, std::mt19937_64& rng) {
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Landmark> lamps;
  for (int i = -3; i <= 3; ++i) {
    for (int j = -3; j <= 3; ++j) {
      Landmark L;
      L.id = lamps.size(), L.p_LinW_m = Eigen::Vector3d(4.5 * i, 4.5 * j, 6.5), L.type = LandmarkType::kTypeI;
      L.cov_LinW_m2 = Eigen::Matrix3d::Identity() * 1e-3;
      lamps.push_back(L);
    }
  }
  f.map.apply({}, lamps);
  MotionNoiseOptions motion;
  const Pose2 prev{u(rng), u(rng), kPi * u(rng)}, step{0.3 + 0.2 * u(rng), 0.02 * u(rng), 0.2 * u(rng)};
  f.pred = stages::predictMotion(prev, step, motion);
  const Eigen::Vector3d sd = f.pred.R.diagonal().cwiseSqrt();
  const Pose2 truth{f.pred.x_hat.x_m + sd(0) * n01(rng), f.pred.x_hat.y_m + sd(1) * n01(rng),
                    f.pred.x_hat.theta_rad + sd(2) * n01(rng)};
  const double sigma_rad = 0.3 * kPi / 180.0;
  for (const Landmark& L : lamps) {
    if ((L.p_LinW_m - cameraCentreInWorld(truth, kCam)).norm() > 9.2) continue;
    const MeasVec z = *predictMeasurement(LandmarkKind::kPoint3D, L.p_LinW_m, truth, kCam);
    BearingMeasurement b;
    b.p_CinR_m = kCam, b.azimuth_rad = wrapAngle(z(0) + sigma_rad * n01(rng));
    b.elevation_rad = z(1) + sigma_rad * n01(rng);
    b.cov_rad2 = Eigen::Matrix2d::Identity() * sigma_rad * sigma_rad;
    f.Z.push_back(*stages::prepareMeasurement(b, f.Z.size(), true, 64.0));
    f.cost_new.push_back(f.Z.back().neg_log_p_new);
  }
  PerceptionOptions per;
  per.max_range_m = 9.5;
  std::vector<LandmarkMap::Ref> near;
  stages::predictVisibleLandmarks(f.map, f.pred.x_hat, kCam, per, near, f.visible);
}

// On 200 such frames: the Hungarian association of the two scores is the same, and so is each
// measurement's order of the landmarks it could be paired with (cost below its "new" cost).
TEST(slam_PairCost, LinearisedRanksPairsAsExactOnLampGridFrames) {
  std::mt19937_64 rng(55);
  int pairs_compared = 0;
  for (int frame = 0; frame < 200; ++frame) {
    GridFrame f;
    makeGridFrame(f, rng);
    ASSERT_GE(f.Z.size(), 5u) << frame;
    const Eigen::MatrixXd exact = stages::scorePairsCorrected(f.visible, f.Z, f.pred);
    const Eigen::MatrixXd lin = stages::scorePairsLinearised(f.visible, f.Z, f.pred);
    EXPECT_EQ(associate(exact, f.cost_new, AssociationMethod::kHungarian),
              associate(lin, f.cost_new, AssociationMethod::kHungarian))
        << "frame " << frame;
    for (Eigen::Index l = 0; l < exact.rows(); ++l) {
      std::vector<Eigen::Index> gated;
      for (Eigen::Index j = 0; j < exact.cols(); ++j)
        if (exact(l, j) < f.cost_new[l] || lin(l, j) < f.cost_new[l]) gated.push_back(j);
      pairs_compared += static_cast<int>(gated.size());
      const auto by = [&](const Eigen::MatrixXd& c) {
        std::vector<Eigen::Index> order = gated;
        std::sort(order.begin(), order.end(), [&](auto a, auto b) { return c(l, a) < c(l, b); });
        return order;
      };
      EXPECT_EQ(by(exact), by(lin)) << "frame " << frame << ", measurement " << l;
    }
  }
  EXPECT_GE(pairs_compared, 1000);
}

// The key: true only with FastSLAM 2.0's corrected score (refused with the reason otherwise); it
// maps to the variant scorePairs dispatches on; association_predictive false keeps it.
TEST(slam_PairCost, KeyMapsToTheVariantAndRefusesWhatHasNoCorrection) {
  const auto& table = slam::options::fastSlamFields();
  const auto field = [&](const std::string& key) {
    return *std::find_if(table.begin(), table.end(), [&](const auto& r) { return r.key == key; });
  };
  const auto lin = field("association_linearised"), predictive = field("association_predictive");
  FastSlamOptions o;
  EXPECT_FALSE(lin.flagMember(o));
  ASSERT_EQ(lin.setFlagMember(o, true), nullptr);
  EXPECT_TRUE(lin.flagMember(o));
  const stages::FilterVariant variant = filterVariantOf(o);
  const auto& score = std::get<stages::FastSlam2>(variant).pair_score;
  ASSERT_TRUE(std::holds_alternative<stages::CorrectedPairScore>(score));
  EXPECT_TRUE(
      std::holds_alternative<stages::LinearisedPairPrediction>(std::get<stages::CorrectedPairScore>(score).prediction));
  ASSERT_EQ(predictive.setFlagMember(o, false), nullptr);
  EXPECT_TRUE(lin.flagMember(o)) << "association_predictive false kept the prediction";

  FastSlamOptions pred;
  ASSERT_EQ(predictive.setFlagMember(pred, true), nullptr);
  EXPECT_EQ(lin.setFlagMember(pred, false), nullptr);
  const char* why = lin.setFlagMember(pred, true);
  ASSERT_NE(why, nullptr);
  EXPECT_NE(std::string(why).find("association_predictive false"), std::string::npos) << why;
  EXPECT_TRUE(predictive.flagMember(pred));

  FastSlamOptions fs1;
  fs1.proposal = FastSlam1Proposal{};
  EXPECT_EQ(lin.setFlagMember(fs1, false), nullptr);
  why = lin.setFlagMember(fs1, true);
  ASSERT_NE(why, nullptr);
  EXPECT_NE(std::string(why).find("needs proposal kFastSlam2"), std::string::npos) << why;
}

}  // namespace
