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
  o.weight_at_predicted_pose = true;
  o.weight_term = WeightTerm::kConsistency;
  o.association_predictive = true;
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

// Exact bearings labelled with their lamp: each landmark keeps its lamp's label, no lamp has two
// landmarks, and each associated measurement went to the landmark of its own lamp.
TEST(OracleFilter, TruthAssociationFollowsTheLabels) {
  const auto lights = scenarios::hallLights();
  OracleFilter f(hallFileOptions(), 7, research::TruthAssociation{});
  f.initialise(scenarios::poseAt(0.0), {});
  const double L = scenarios::loopLength();
  Pose2 prev = scenarios::poseAt(0.0);
  int checked = 0;
  for (double s = 0.27; s <= L; s += 0.27) {
    const Pose2 x = scenarios::poseAt(s);
    std::vector<BearingMeasurement> z;
    std::vector<std::int64_t> label;
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
