// research_test_oracle_filter: the recomposed step (oracle_filter.h) with the filter's own association
// is FastSlam bit for bit (poses and maps after every step, several variants); with the truth
// association every landmark takes only the measurements of its own lamp.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "oracle_filter.h"
#include "slam_scenarios.h"

using namespace omnislam;
using namespace omnislam::slam;
using research::OracleFilter;

namespace {

// The deviations of config/slam/sports_hall.yaml from the recommended preset that change the step.
FastSlamOptions hallFileOptions() {
  FastSlamOptions o;
  o.resample_ess_fraction = 0.5;
  std::get<FastSlam2Proposal>(o.proposal).weight = stages::WeightAtPredictedPose{};
  o.weight_term = ConsistencyTerm{};
  std::get<FastSlam2Proposal>(o.proposal).pair_score = stages::PredictivePairScore{};
  o.odometry_scale_correction = true;
  o.candidates.min_ray_baseline_m = 0.2;
  o.perception.detection_probability = 0.9;
  return o;
}

void expectSameAsFastSlam(const FastSlamOptions& o, std::uint64_t seed) {
  const auto frames = scenarios::simulateHall(seed);
  FastSlam ref(o, seed);
  OracleFilter rec(o, seed, research::FilterAssociation{});
  ref.initialise(frames[0].truth);
  rec.initialise(frames[0].truth, {});
  for (std::size_t k = 1; k < frames.size(); ++k) {
    const StepResult a = ref.step(frames[k - 1].odom, frames[k].odom, frames[k].z);
    const research::OracleStep b = rec.step(frames[k - 1].odom, frames[k].odom, frames[k].z);
    ASSERT_EQ(a.ess, b.ess) << "step " << k;
    ASSERT_EQ(a.landmark_of_measurement, b.landmark_of_measurement) << "step " << k;
    ASSERT_EQ(ref.meanPose().vec(), rec.meanPose().vec()) << "step " << k;
    const auto ma = ref.bestMap(), mb = rec.bestMap();
    ASSERT_EQ(ma.size(), mb.size()) << "step " << k;
    for (std::size_t i = 0; i < ma.size(); ++i) {
      ASSERT_EQ(ma[i].id, mb[i].id);
      ASSERT_EQ(ma[i].p_LinW_m, mb[i].p_LinW_m);
      ASSERT_EQ(ma[i].cov_LinW_m2, mb[i].cov_LinW_m2);
    }
  }
  EXPECT_GT(ref.bestMap().size(), 0u);  // the comparison covered landmarks, not only an empty map
}

}  // namespace

TEST(OracleFilter, FilterAssociationIsFastSlamBitForBit) { expectSameAsFastSlam(hallFileOptions(), 3); }

TEST(OracleFilter, FilterAssociationIsFastSlamWithThePaperSettings) {
  FastSlamOptions o = presetOptions(Preset::kPaper000);
  expectSameAsFastSlam(o, 4);
  o.association = AssociationMethod::kMaximumLikelihood;
  expectSameAsFastSlam(o, 5);
}

TEST(OracleFilter, LabelRoundTrip) {
  EXPECT_EQ(research::labelOf(research::labelDescriptor(0)), 0);
  EXPECT_EQ(research::labelOf(research::labelDescriptor(123456)), 123456);
  EXPECT_EQ(research::labelOf(ColourDescriptor{}), -1);
}

// Exact bearings from the truth pose at arc length s, each labelled with its lamp (index in hallLights()).
std::vector<BearingMeasurement> labelledBearings(const Pose2& x, std::vector<std::int64_t>& label) {
  const auto lights = scenarios::hallLights();
  std::vector<BearingMeasurement> z;
  for (std::size_t i = 0; i < lights.size(); ++i) {
    const auto zt = predictMeasurement(LandmarkKind::kPoint3D, lights[i], x, scenarios::kCamInR);
    if (!zt || (*zt)(1) < -5.0 * kPi / 180.0) continue;
    BearingMeasurement m;
    m.azimuth_rad = (*zt)(0);
    m.elevation_rad = (*zt)(1);
    m.p_CinR_m = scenarios::kCamInR;
    m.descriptor = research::labelDescriptor(static_cast<std::int64_t>(i));
    z.push_back(m);
    label.push_back(static_cast<std::int64_t>(i));
  }
  return z;
}

// Each landmark keeps its lamp's label, no lamp has two landmarks, and each associated measurement
// went to the landmark of its own lamp.
TEST(OracleFilter, TruthAssociationFollowsTheLabels) {
  OracleFilter f(hallFileOptions(), 7, research::TruthAssociation{});
  f.initialise(scenarios::poseAt(0.0), {});
  Pose2 prev = scenarios::poseAt(0.0);
  int checked = 0;
  for (double s = 0.27; s <= scenarios::loopLength(); s += 0.27) {
    const Pose2 x = scenarios::poseAt(s);
    std::vector<std::int64_t> label;
    const std::vector<BearingMeasurement> z = labelledBearings(x, label);
    const research::OracleStep st = f.step(prev, x, z);
    prev = x;
    std::map<std::uint64_t, std::int64_t> label_of_id;
    std::set<std::int64_t> labels;
    for (const Landmark& lm : f.bestMap()) {
      label_of_id[lm.id] = research::labelOf(lm.descriptor);
      EXPECT_TRUE(labels.insert(research::labelOf(lm.descriptor)).second) << "two landmarks of one lamp";
    }
    for (std::size_t l = 0; l < z.size(); ++l) {
      const auto it = label_of_id.find(static_cast<std::uint64_t>(st.landmark_of_measurement[l]));
      if (st.landmark_of_measurement[l] < 0 || it == label_of_id.end()) continue;
      EXPECT_EQ(it->second, label[l]);
      ++checked;
    }
  }
  EXPECT_GT(f.bestMap().size(), 0u);
  EXPECT_GT(checked, 0);
}

// With TruthBirth every landmark stands at its lamp's position at the end of the step that initialises it.
TEST(OracleFilter, TruthBirthPutsNewLandmarksAtTheirLamps) {
  const auto lights = scenarios::hallLights();
  research::TruthBirth birth;
  for (std::size_t i = 0; i < lights.size(); ++i) birth.p_LinW_m[static_cast<std::int64_t>(i)] = lights[i];
  FastSlamOptions o = hallFileOptions();
  o.num_particles = 1;  // a landmark new to the best map is then one born in this step
  OracleFilter f(o, 8, research::TruthAssociation{}, birth);
  f.initialise(scenarios::poseAt(0.0), {});
  Pose2 prev = scenarios::poseAt(0.0);
  std::set<std::uint64_t> known;
  int born = 0;
  for (double s = 0.27; s <= scenarios::loopLength(); s += 0.27) {
    const Pose2 x = scenarios::poseAt(s);
    std::vector<std::int64_t> label;
    f.step(prev, x, labelledBearings(x, label));
    prev = x;
    for (const Landmark& lm : f.bestMap()) {
      if (!known.insert(lm.id).second) continue;
      EXPECT_EQ(lm.p_LinW_m, lights[static_cast<std::size_t>(research::labelOf(lm.descriptor))]);
      ++born;
    }
  }
  EXPECT_GT(born, 0);
}
