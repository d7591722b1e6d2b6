// omnislam-eval's association precision / recall (SLAM_ASSOCIATIONS against
// GROUND_TRUTH_FEATURE_LABELS, through the eval's landmark assignment) and dead reckoning's figures
// (ODOMETRY mapped into the truth frame by the start pose, raw and aligned) on a synthetic log with
// known answers; plus the pure functions behind them.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>

#include "omnislam/associations_t.hpp"
#include "omnislam/eval/metrics.h"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "eval_json.h"
#include "omnislam/lcmio/log_writer.h"
#include "proc_util.h"
#include "slam_log.h"

using namespace omnislam;
namespace t = omnislam::testing;
using omnislam::testing::jsonNumber;

namespace {

int64_t utimeOf(int k) { return 1'000'000 + static_cast<int64_t>(k) * 100'000; }

// Truth: x = 0.1 k along +x. Odometry: 10 % long, in a frame rotated by +90 deg and shifted, so
// only the start-pose mapping makes it comparable. SLAM: exactly the truth at k = 0, 10, ..., 100.
// Map: 100 -> true 6 (0.1 m off), 101 -> true 7, 102 a ghost. Features per frame i (k = 10 i):
//   [label 6 -> 100 correct] [label 7 -> 100 wrong] [robot -> 101 clutter] [label 8 -> none]
//   + even i: [label 7 -> 101 correct]; + odd i: [label 8 -> NOT_USED].
// Plus a frame with labels but no SLAM answer (ignored) and one whose association has the wrong
// number of entries (left out, counted).
void makeLog(const std::string& path) {
  lcmio::LogWriter log(path);
  log.write(utimeOf(0), channels::kGroundTruthMap,
            t::makeLineMap({{6, {1.0, 1.1}}, {7, {2.0, -1.0}}, {8, {3.0, 1.0}}}));
  for (int k = 0; k <= 110; ++k) {
    const int64_t u = utimeOf(k);
    log.write(u, channels::kGroundTruthPose, t::makePose(u, 0.1 * k, 0.0, 0.0));
    odometry_t o{};
    o.utime = u;
    o.seq = k;
    o.x_m = 5.0;
    o.y_m = 3.0 + 0.11 * k;
    o.theta_rad = M_PI / 2;
    log.write(u, channels::kOdometry, o);
    if (k % 10 == 0 && k <= 100) {
      const int i = k / 10;
      std::vector<int64_t> lab{6, 7, +feature_labels_t::OTHER_ROBOT, 8};
      std::vector<int64_t> ass{100, 100, 101, +associations_t::NOT_ASSOCIATED};
      if (i % 2 == 0) {
        lab.push_back(7);
        ass.push_back(101);
      } else {
        lab.push_back(8);
        ass.push_back(+associations_t::NOT_USED);
      }
      features_t f{};
      f.utime = u;
      f.seq = i;
      f.num_features = static_cast<int32_t>(lab.size());
      f.features.resize(lab.size());
      log.write(u, channels::kOmniFeatures, f);
      feature_labels_t fl{};
      fl.utime = u;
      fl.seq = i;
      fl.features_seq = i;
      fl.num_features = f.num_features;
      fl.landmark_id = lab;
      fl.source_code.assign(lab.size(), -1);
      log.write(u, channels::kGroundTruthFeatureLabels, fl);
      log.write(u, channels::kSlamPose, t::makePose(u, 0.1 * k, 0.0, 0.0));
      associations_t a{};
      a.utime = u;
      a.seq = i;
      a.input_seq = i;
      a.num_features = f.num_features;
      a.landmark_id = ass;
      log.write(u, channels::kSlamAssociations, a);
      log.write(u, channels::kSlamMap, t::makeLineMap({{100, {1.0, 1.0}}, {101, {2.0, -1.0}}, {102, {5.0, 5.0}}}));
    }
    if (k == 95 || k == 105) {  // labels for a frame the SLAM answered badly (95) or not at all (105)
      feature_labels_t fl{};
      fl.utime = u;
      fl.seq = 100 + k;
      fl.features_seq = 100 + k;
      fl.num_features = 3;
      fl.landmark_id = {6, 7, 8};
      fl.source_code = {-1, -1, -1};
      log.write(u, channels::kGroundTruthFeatureLabels, fl);
      if (k == 95) {
        associations_t a{};
        a.utime = u;
        a.num_features = 2;
        a.landmark_id = {100, 101};
        log.write(u, channels::kSlamAssociations, a);
      }
    }
  }
}

TEST(EvalAssociation, PrecisionRecallAndDeadReckoningKnownAnswers) {
  t::TempDir d;
  const std::string log = d.file("run.lcm");
  makeLog(log);
  for (const bool align : {false, true}) {
    std::vector<std::string> argv{t::binPath("omnislam-eval"), log, "--json", "--no-tum", "--planar"};
    if (align) argv.push_back("--align");
    const auto r = t::run(argv, 60);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::string& j = r.output;
    // Existing keys unchanged.
    EXPECT_NEAR(jsonNumber(j, "ate_rmse_m"), 0.0, 1e-9) << j;
    EXPECT_EQ(jsonNumber(j, "landmarks_matched"), 2) << j;
    EXPECT_EQ(jsonNumber(j, "landmarks_spurious"), 1) << j;
    EXPECT_NEAR(jsonNumber(j, "landmark_mean_err_m"), 0.05, 1e-9) << j;
    // Association: 11 frames scored, 1 mismatched; 17 correct of 39 associated, of 44 true features.
    EXPECT_NE(j.find("\"assoc_available\": true"), std::string::npos) << j;
    EXPECT_EQ(jsonNumber(j, "assoc_frames"), 11) << j;
    EXPECT_EQ(jsonNumber(j, "assoc_frames_mismatched"), 1) << j;
    EXPECT_EQ(jsonNumber(j, "assoc_features"), 11 * 5) << j;
    EXPECT_EQ(jsonNumber(j, "assoc_associated"), 39) << j;
    EXPECT_EQ(jsonNumber(j, "assoc_correct"), 17) << j;
    EXPECT_EQ(jsonNumber(j, "assoc_true_landmark_features"), 44) << j;
    EXPECT_EQ(jsonNumber(j, "assoc_clutter_associated"), 11) << j;
    EXPECT_NEAR(jsonNumber(j, "assoc_precision"), 17.0 / 39.0, 1e-5) << j;
    EXPECT_NEAR(jsonNumber(j, "assoc_recall"), 17.0 / 44.0, 1e-5) << j;
    // Dead reckoning at the 11 SLAM poses: error 0.01 k = 0.1 i -> RMSE 0.1 sqrt(35), max 1.0;
    // aligned (translation -0.5 m along x): errors |0.1 i - 0.5| -> RMSE 0.1 sqrt(10), max 0.5.
    EXPECT_NE(j.find("\"dr_available\": true"), std::string::npos) << j;
    EXPECT_EQ(jsonNumber(j, "dr_poses_compared"), 11) << j;
    EXPECT_NEAR(jsonNumber(j, "dr_ate_rmse_m"), 0.1 * std::sqrt(35.0), 1e-5) << j;
    EXPECT_NEAR(jsonNumber(j, "dr_ate_max_m"), 1.0, 1e-5) << j;
    EXPECT_NEAR(jsonNumber(j, "dr_heading_rmse_rad"), 0.0, 1e-9) << j;
    EXPECT_NEAR(jsonNumber(j, "dr_ate_rmse_aligned_m"), 0.1 * std::sqrt(10.0), 1e-5) << j;
    EXPECT_NEAR(jsonNumber(j, "dr_ate_max_aligned_m"), 0.5, 1e-5) << j;
  }
  // The table carries the same figures.
  const auto r = t::run({t::binPath("omnislam-eval"), log, "--no-tum", "--planar"}, 60);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("association: precision 0.435897 (17/39), recall 0.386364 (17/44)"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("dead reckoning"), std::string::npos) << r.output;
}

TEST(EvalAssociation, WithoutLabelsNoAssociationKeys) {
  t::TempDir d;
  const std::string log = d.file("plain.lcm");
  {
    lcmio::LogWriter f(log);
    f.write(utimeOf(0), channels::kGroundTruthMap, t::makeLineMap({{6, {1.0, 1.0}}}));
    for (int k = 0; k <= 10; ++k) {
      f.write(utimeOf(k), channels::kGroundTruthPose, t::makePose(utimeOf(k), 0.1 * k, 0.0, 0.0));
      f.write(utimeOf(k), channels::kSlamPose, t::makePose(utimeOf(k), 0.1 * k, 0.0, 0.0));
    }
    f.write(utimeOf(10), channels::kSlamMap, t::makeLineMap({{100, {1.0, 1.0}}}));
  }
  const auto r = t::run({t::binPath("omnislam-eval"), log, "--json", "--no-tum"}, 60);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\"assoc_available\": false"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"dr_available\": false"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("assoc_precision"), std::string::npos) << r.output;
}

TEST(EvalAssociationMetrics, ScoreAssociations) {
  const std::map<int64_t, int64_t> truth_of{{100, 6}, {101, 7}};
  const auto s =
      eval::scoreAssociations({{100, 101, 102, -2}, {101, -1}, {100}}, {{6, 6, 7, 7}, {7, -1}, {6, 8}}, truth_of);
  EXPECT_EQ(s.frames, 2);
  EXPECT_EQ(s.frames_mismatched, 1);
  EXPECT_EQ(s.features, 6);
  EXPECT_EQ(s.true_landmark_features, 5);
  EXPECT_EQ(s.associated, 4);  // 100, 101, 102, 101
  EXPECT_EQ(s.correct, 2);     // 100 -> 6, 101 -> 7 in frame 2
  EXPECT_EQ(s.clutter_associated, 0);
  EXPECT_DOUBLE_EQ(s.precision(), 0.5);
  EXPECT_DOUBLE_EQ(s.recall(), 0.4);
  const auto empty = eval::scoreAssociations({}, {}, truth_of);
  EXPECT_EQ(empty.precision(), 0.0);
  EXPECT_EQ(empty.recall(), 0.0);
}

TEST(EvalAssociationMetrics, RigidFromPosesAndPoseAt) {
  const Pose2 from{5.0, 3.0, M_PI / 2}, to{1.0, -2.0, 0.3};
  const eval::Rigid2D T = eval::rigidFromPoses(from, to);
  const Pose2 m = T.apply(from);
  EXPECT_NEAR(m.x_m, to.x_m, 1e-12);
  EXPECT_NEAR(m.y_m, to.y_m, 1e-12);
  EXPECT_NEAR(m.theta_rad, to.theta_rad, 1e-12);
  // A pose 1 m ahead of `from` lands 1 m ahead of `to`.
  const Pose2 ahead = T.apply(from.compose({1.0, 0.0, 0.0}));
  EXPECT_NEAR(ahead.x_m, to.x_m + std::cos(0.3), 1e-12);
  EXPECT_NEAR(ahead.y_m, to.y_m + std::sin(0.3), 1e-12);

  const std::vector<eval::TimedPose> tr{{0, {0.0, 0.0, 0.0}}, {10, {1.0, 2.0, 0.2}}, {100, {5.0, 5.0, 0.0}}};
  EXPECT_NEAR(eval::poseAt(tr, 5, 20)->y_m, 1.0, 1e-12);
  EXPECT_NEAR(eval::poseAt(tr, 10, 20)->x_m, 1.0, 1e-12);
  EXPECT_FALSE(eval::poseAt(tr, 50, 20).has_value());  // across a gap of 90 > 20
  EXPECT_FALSE(eval::poseAt(tr, -1, 20).has_value());
  EXPECT_FALSE(eval::poseAt(tr, 101, 200).has_value());
}

}  // namespace
