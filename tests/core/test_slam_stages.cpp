// Tests of the filter's stages on their own (filter_stages.h, landmark_type.h): the hierarchical
// association's level 1 against brute force, the proposal without associations, the miss rule of
// Alg. 4, and the type I/II rule.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <type_traits>

#include "omnislam/core/slam/filter_stages.h"
#include "omnislam/core/slam/landmark_type.h"
#include "omnislam/core/slam/options_table.h"

namespace {

using namespace omnislam;
using namespace omnislam::slam;
constexpr double kInf = std::numeric_limits<double>::infinity();

// The least total cost over every joint assignment (each measurement a landmark or "new", each
// landmark at most once), by enumeration.
double bruteForceMinimum(const Eigen::MatrixXd& cost, const std::vector<double>& cost_new) {
  const int nz = static_cast<int>(cost.rows()), n = static_cast<int>(cost.cols());
  double best = kInf;
  std::vector<int> a(nz, -1);
  while (true) {
    bool ok = true;
    double total = 0.0;
    for (int l = 0; l < nz && ok; ++l) {
      if (a[l] < 0) {
        total += cost_new[l];
        continue;
      }
      ok = std::isfinite(cost(l, a[l]));
      for (int k = 0; k < l && ok; ++k) ok = a[k] != a[l];
      total += ok ? cost(l, a[l]) : 0.0;
    }
    if (ok) best = std::min(best, total);
    int l = 0;
    while (l < nz && ++a[l] == n) a[l++] = -1;
    if (l == nz) break;
  }
  return best;
}

// Level 1 of the hierarchical association is the minimum-cost assignment; the proposal runs once,
// between the levels, on level 1's result; level 2's rows are exactly the measurements level 1 left.
TEST(slam_Stages, HierarchicalAssociationLevel1IsTheBruteForceMinimumAndFeedsTheProposal) {
  std::mt19937_64 gen(5);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  const FastSlamOptions options;
  const std::vector<std::shared_ptr<const Candidate>> no_candidates;
  const std::vector<stages::Measurement> no_measurements;
  for (int trial = 0; trial < 100; ++trial) {
    const int nz = 1 + trial % 4, n = trial % 5;
    Eigen::MatrixXd cost(nz, n);
    std::vector<double> cost_new(nz);
    for (int l = 0; l < nz; ++l) {
      cost_new[l] = u(gen);
      for (int j = 0; j < n; ++j) cost(l, j) = u(gen) < 4.0 ? kInf : u(gen);
    }
    const stages::MapLevelInput level1{cost, cost_new, stages::HungarianAssociation{}};
    const stages::CandidateLevelInput level2{
        no_candidates,
        no_measurements,
        RangeLimits{options.perception.min_range_m, options.perception.max_range_m},
        stages::HungarianAssociation{},
        false,
        nullptr};
    int calls = 0;
    const Pose2 proposed{1.0, 2.0, 0.5};
    const auto propose = [&](const stages::MapAssociation& l1) {
      ++calls;
      EXPECT_EQ(l1.landmark_of_measurement.size(), static_cast<size_t>(nz));
      return proposed;
    };
    const stages::HierarchicalAssociation a = stages::associateHierarchically(level1, propose, level2);
    EXPECT_EQ(calls, 1);
    EXPECT_EQ(a.x_t.vec(), proposed.vec());
    double total = 0.0;
    std::vector<int> leftover;
    for (int l = 0; l < nz; ++l) {
      const int j = a.level1.landmark_of_measurement[l];
      if (j < 0) leftover.push_back(l);
      total += j < 0 ? cost_new[l] : cost(l, j);
    }
    EXPECT_NEAR(total, bruteForceMinimum(cost, cost_new), 1e-9) << "trial " << trial;
    EXPECT_EQ(a.leftover, leftover);
    EXPECT_TRUE(a.candidate_of_leftover.empty());  // level 2 disabled (localisation only)
  }
}

// Alg. 3 line 2: without associations the FastSLAM 2.0 proposal is the motion model (same draw).
TEST(slam_Stages, ProposalWithoutAssociationsIsTheMotionModel) {
  const stages::MotionPrediction pred = stages::predictMotion({1.0, 0.0, 0.2}, {0.5, 0.0, 0.1}, MotionNoiseOptions{});
  Rng ra(7), rb(7);
  ParticleRng a = ParticleRng::drawFrom(ra), b = ParticleRng::drawFrom(rb);
  const Pose2 x = stages::sampleFastSlam2Pose(pred, {}, {}, {-1, -1}, a);
  const Pose2 y = stages::sampleMotionModel(pred, b);
  EXPECT_EQ(x.vec(), y.vec());
  EXPECT_NE(x.vec(), pred.x_hat.vec());
}

// Alg. 4 lines 18-25: an unseen landmark in range costs log(1 - p_in) and loses one count; at a
// negative count it is deleted; one out of range is left alone.
TEST(slam_Stages, MissesCountDownAndDelete) {
  FastSlamOptions o;
  o.perception.max_range_m = 10.0;
  LandmarkMap map(o.map_cell_size_m);
  Landmark seen_often, last_chance, far;
  seen_often.id = 1, seen_often.p_LinW_m = Eigen::Vector3d(3.0, 0.0, 2.0), seen_often.counter = 4;
  last_chance.id = 2, last_chance.p_LinW_m = Eigen::Vector3d(0.0, 3.0, 2.0), last_chance.counter = 0;
  far.id = 3, far.p_LinW_m = Eigen::Vector3d(40.0, 0.0, 2.0);
  map.apply({}, {seen_often, last_chance, far});
  stages::ParticleUpdate up;
  std::vector<LandmarkMap::Ref> near;
  stages::accountMisses(map, Pose2{0.0, 0.0, 0.0}, Eigen::Vector3d::Zero(), o.perception, o.update_map, near, up);
  EXPECT_DOUBLE_EQ(up.log_w, 2.0 * std::log(1.0 - o.perception.detection_probability));
  ASSERT_EQ(up.edits.size(), 2u);
  EXPECT_EQ(up.num_deleted, 1);
  for (const auto& e : up.edits) {
    EXPECT_NE(e.value.id, far.id);
    EXPECT_EQ(e.erase, e.value.id == last_chance.id);
    EXPECT_EQ(e.value.counter, (e.value.id == seen_often.id ? 3 : -1));
  }
}

// Sec. III-F 2: type I when both poses of the cross-point are within D_min; a type II landmark is
// promoted when observed from within D_min, and a type I never demoted.
TEST(slam_Stages, TypeIAndIIRule) {
  const Eigen::Vector3d p(5.0, 0.0, 2.5);
  const double d_min = 8.0;
  EXPECT_EQ(initialLandmarkType({0, 0, 0}, {1, 0, 0}, p, d_min), LandmarkType::kTypeI);
  EXPECT_EQ(initialLandmarkType({0, 0, 0}, {-4, 0, 0}, p, d_min), LandmarkType::kTypeII);  // 9 m from one pose
  Landmark l;
  l.p_LinW_m = p;
  l.type = LandmarkType::kTypeII;
  EXPECT_EQ(promotedLandmarkType(l, {-3.5, 0, 0}, d_min), LandmarkType::kTypeII);
  EXPECT_EQ(promotedLandmarkType(l, {-2.5, 0, 0}, d_min), LandmarkType::kTypeI);
  l.type = LandmarkType::kTypeI;
  EXPECT_EQ(promotedLandmarkType(l, {-30, 0, 0}, d_min), LandmarkType::kTypeI);
  EXPECT_TRUE(correctsPoseAndWeighs(l));
  l.type = LandmarkType::kTypeII;
  EXPECT_FALSE(correctsPoseAndWeighs(l));
}

// The options map to one variant; a combination that makes no sense (a pair score for FastSLAM 1.0,
// which has none) cannot be written in the options, and the table's key refuses it with its reason.
TEST(slam_Stages, OptionsMapToOneVariant) {
  FastSlamOptions o;
  const stages::FilterVariant paper = filterVariantOf(o);
  ASSERT_TRUE(std::holds_alternative<stages::FastSlam2>(paper));
  EXPECT_TRUE(std::holds_alternative<stages::CorrectedPairScore>(std::get<stages::FastSlam2>(paper).pair_score));
  EXPECT_TRUE(std::holds_alternative<stages::WeightAlg4>(stages::weightingOf(paper)));
  EXPECT_TRUE(std::holds_alternative<stages::HungarianAssociation>(stages::associationOf(paper)));

  o.proposal = FastSlam1Proposal{};
  o.association = AssociationMethod::kMaximumLikelihood;
  EXPECT_TRUE(std::holds_alternative<stages::FastSlam1>(filterVariantOf(o)));
  EXPECT_TRUE(std::holds_alternative<stages::WeightMarginal>(stages::weightingOf(filterVariantOf(o))));
  EXPECT_TRUE(std::holds_alternative<stages::MaximumLikelihoodAssociation>(stages::associationOf(filterVariantOf(o))));

  // The keys of FastSLAM 2.0's choices: refused while the proposal is FastSLAM 1.0, "false" accepted.
  for (const char* key : {"association_predictive", "weight_at_predicted_pose"}) {
    const auto& table = slam::options::fastSlamFields();
    const auto f = std::find_if(table.begin(), table.end(), [&](const auto& r) { return std::string(r.key) == key; });
    ASSERT_NE(f, table.end()) << key;
    EXPECT_EQ(f->setFlagMember(o, false), nullptr) << key;
    const char* why = f->setFlagMember(o, true);
    ASSERT_NE(why, nullptr) << key;
    EXPECT_NE(std::string(why).find("needs proposal kFastSlam2"), std::string::npos) << why;
    EXPECT_TRUE(std::holds_alternative<FastSlam1Proposal>(o.proposal)) << key;
    FastSlamOptions fs2;
    EXPECT_EQ(f->setFlagMember(fs2, true), nullptr) << key;
    EXPECT_TRUE(f->flagMember(fs2)) << key;
  }
  FastSlamOptions fs2;
  std::get<FastSlam2Proposal>(fs2.proposal).pair_score = stages::PredictivePairScore{};
  EXPECT_TRUE(std::holds_alternative<stages::PredictivePairScore>(
      std::get<stages::FastSlam2>(filterVariantOf(fs2)).pair_score));
}

// The detection counter: +1 at p_in >= 0.5, otherwise enough that the nominal rate does not drift down.
TEST(slam_Stages, HitIncrement) {
  EXPECT_EQ(stages::hitIncrement(0.9), 1);
  EXPECT_EQ(stages::hitIncrement(0.5), 1);
  EXPECT_EQ(stages::hitIncrement(0.25), 3);
  EXPECT_EQ(stages::hitIncrement(0.4), 2);
}

}  // namespace

namespace {

// One type I landmark at p (covariance cov) observed exactly from the true pose: updateObservedLandmarks'
// weight term under the given weighting and form.
double exactObservationWeight(const Eigen::Matrix3d& cov, const WeightTerm& form, const stages::Weighting& weighting) {
  FastSlamOptions o;
  o.weight_term = form;
  LandmarkMap map(o.map_cell_size_m);
  Landmark L;
  L.id = 1, L.p_LinW_m = Eigen::Vector3d(3.0, 1.0, 4.0), L.cov_LinW_m2 = cov, L.type = LandmarkType::kTypeI;
  map.apply({}, {L});
  std::vector<LandmarkMap::Ref> all;
  map.collectAll(all);
  const Pose2 x{0.5, -0.2, 0.3};
  const Eigen::Vector3d cam(0.0, 0.0, 1.0);
  BearingMeasurement b;
  const MeasVec z = *predictMeasurement(LandmarkKind::kPoint3D, L.p_LinW_m, x, cam);
  b.azimuth_rad = z(0), b.elevation_rad = z(1), b.p_CinR_m = cam;
  b.cov_rad2 = Eigen::Matrix2d::Identity() * 1e-5;
  const std::vector<stages::Measurement> Z{*stages::prepareMeasurement(b, 0, true, o.p_new_mahalanobis_sq)};
  MotionNoiseOptions motion;
  const stages::MotionPrediction pred = stages::predictMotion(x, Pose2{0.0, 0.0, 0.0}, motion);
  stages::ParticleUpdate up;
  stages::updateObservedLandmarks(pred, x, all, Z, {0}, stages::landmarkUpdateOptionsOf(o), weighting, up);
  return up.log_w;
}

}  // namespace

// Alg. 4 line 14's density rewards a particle for the confidence of its own landmark (at equal,
// zero residuals the one with the smaller covariance weighs more); the consistency term gives both
// exactly +dim/2 (residual 0: -1/2 (0 - 2)), whatever their covariances, under every FastSLAM weighting.
TEST(slam_Stages, ConsistencyWeightTermDoesNotRewardAConfidentMap) {
  const Eigen::Matrix3d sure = Eigen::Matrix3d::Identity() * 1e-4, unsure = Eigen::Matrix3d::Identity() * 1e-2;
  for (const stages::Weighting& w :
       {stages::Weighting{stages::WeightAlg4{}}, stages::Weighting{stages::WeightAtPredictedPose{}},
        stages::Weighting{stages::WeightMarginal{}}}) {
    EXPECT_GT(exactObservationWeight(sure, DensityTerm{}, w), exactObservationWeight(unsure, DensityTerm{}, w) + 1.0);
    EXPECT_NEAR(exactObservationWeight(sure, ConsistencyTerm{}, w), 1.0, 1e-9);
    EXPECT_NEAR(exactObservationWeight(unsure, ConsistencyTerm{}, w), 1.0, 1e-9);
  }
}

// The consistency term is the density less its normaliser and the Mahalanobis expectation, checked
// in closed form on a residual: -1/2 (nu^T L^-1 nu - dim) = log N(nu; 0, L) + 1/2 log|2 pi L| + dim/2.
TEST(slam_Stages, ConsistencyWeightTermIsTheDensityWithoutItsNormaliser) {
  FastSlamOptions o;
  LandmarkMap map(o.map_cell_size_m);
  Landmark L;
  L.id = 1, L.p_LinW_m = Eigen::Vector3d(2.0, -1.0, 3.0), L.cov_LinW_m2 = Eigen::Matrix3d::Identity() * 4e-3;
  L.type = LandmarkType::kTypeI;
  map.apply({}, {L});
  std::vector<LandmarkMap::Ref> all;
  map.collectAll(all);
  const Pose2 x{0.0, 0.0, 0.1};
  BearingMeasurement b;
  const MeasVec z = *predictMeasurement(LandmarkKind::kPoint3D, L.p_LinW_m, x, Eigen::Vector3d::Zero());
  b.azimuth_rad = z(0) + 0.01, b.elevation_rad = z(1) - 0.02;
  b.cov_rad2 << 2e-4, 3e-5, 3e-5, 1e-4;
  const stages::Measurement m = *stages::prepareMeasurement(b, 0, false, o.p_new_mahalanobis_sq);
  const stages::MotionPrediction pred = stages::predictMotion(x, Pose2{0.0, 0.0, 0.0}, o.motion);
  double log_w[2];
  for (const WeightTerm& form : {WeightTerm{DensityTerm{}}, WeightTerm{ConsistencyTerm{}}}) {
    o.weight_term = form;
    stages::ParticleUpdate up;
    stages::updateObservedLandmarks(pred, x, all, {m}, {0}, stages::landmarkUpdateOptionsOf(o),
                                    stages::WeightMarginal{}, up);
    log_w[form.index()] = up.log_w;
  }
  // WeightMarginal's L is Q~ = Q + H_m Sigma H_m^T at x (the EKF's innovation covariance).
  MeasJac Hx, Hm;
  const MeasVec zhat = *predictMeasurement(LandmarkKind::kPoint3D, L.p_LinW_m, x, Eigen::Vector3d::Zero(), &Hx, &Hm);
  const MeasMat S = m.Q + Hm * L.cov_LinW_m2 * Hm.transpose();
  const MeasVec nu = innovation(m.z, zhat);
  const double m2 = nu.dot(S.inverse() * nu);
  EXPECT_NEAR(log_w[1], -0.5 * (m2 - 2.0), 1e-9);
  EXPECT_NEAR(log_w[0], -0.5 * (m2 + std::log((2.0 * kPi * S).determinant())), 1e-9);
}

// Under the consistency term a measurement that neither the map nor a candidate takes costs what an
// association at the P_new gate would score, -1/2 (p_new_mahalanobis_sq - dim); one a candidate takes
// costs nothing; the density term adds nothing here (the paper).
TEST(slam_Stages, UnexplainedMeasurementsCostTheGatesConsistencyTerm) {
  FastSlamOptions o;
  std::vector<stages::Measurement> Z(3);
  Z[0].z = MeasVec::Zero(2), Z[1].z = MeasVec::Zero(2), Z[2].z = MeasVec::Zero(1);
  stages::HierarchicalAssociation a;
  a.level1.landmark_of_measurement = {0, -1, -1};
  a.leftover = {1, 2};
  a.candidate_of_leftover = {4, -1};  // measurement 1 to candidate 4, measurement 2 new
  EXPECT_EQ(stages::unexplainedWeight(a, Z, o.weight_term, o.p_new_mahalanobis_sq), 0.0);
  o.weight_term = ConsistencyTerm{};
  EXPECT_DOUBLE_EQ(stages::unexplainedWeight(a, Z, o.weight_term, o.p_new_mahalanobis_sq),
                   -0.5 * (o.p_new_mahalanobis_sq - 1.0));
  a.candidate_of_leftover.clear();  // no level 2 (localisation only): every leftover is unexplained
  EXPECT_DOUBLE_EQ(stages::unexplainedWeight(a, Z, o.weight_term, o.p_new_mahalanobis_sq),
                   -0.5 * (o.p_new_mahalanobis_sq - 2.0) - 0.5 * (o.p_new_mahalanobis_sq - 1.0));
}
