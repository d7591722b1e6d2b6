// The SLAM process's shared code path (common/runtime/include/omnislam/runtime/slam_driver.h): message conversion,
// outputs stamped with the frame's utime and answering its seq, determinism, and degraded input that never corrupts the
// filter.
#include <gtest/gtest.h>

#include <sstream>

#include <algorithm>
#include <set>
#include <cmath>
#include <limits>

#include "omnislam/core/angles.h"
#include "omnislam/runtime/slam_driver.h"
#include "slam_inputs.h"

using namespace omnislam;
using namespace omnislam::runtime;
using namespace omnislam::testing;

namespace {

/// Feeds `seconds` of 50 Hz odometry and 1 Hz frames, frames arriving 100 ms late.
std::vector<FrameOutput> run(SlamDriver& d, int seconds, int64_t t0 = kT0) {
  std::vector<FrameOutput> outs;
  int64_t oseq = 0, fseq = 0;
  for (int64_t t = t0; t <= t0 + seconds * 1'000'000LL; t += 20'000) {
    for (auto& o : d.onOdometry(hallOdometry(t, oseq++)).outputs) outs.push_back(std::move(o));
    if (t - 100'000 >= t0 && (t - 100'000 - t0) % 1'000'000 == 0)
      for (auto& o : d.onFeatures(hallFeatures(t - 100'000, fseq++)).outputs) outs.push_back(std::move(o));
  }
  return outs;
}

TEST(ToMeasurement, ConvertsKindsAndSkipsWhatIsOffOrIncomplete) {
  SlamProcessOptions o;
  const double cam[3] = {0.1, -0.2, 1.8};
  feature_t f{};
  f.kind = feature_t::KIND_CEILING_LIGHT;
  f.azimuth_rad = 0.5;
  f.elevation_rad = 1.0;
  f.has_elevation = true;
  f.covariance[0][0] = 1e-4;
  f.covariance[0][1] = f.covariance[1][0] = 1e-6;
  f.covariance[1][1] = 2e-4;
  auto m = toMeasurement(f, cam, o);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->kind, slam::LandmarkKind::kPoint3D);
  EXPECT_EQ(m->azimuth_rad, 0.5);
  EXPECT_EQ(m->elevation_rad, 1.0);
  EXPECT_EQ(m->cov_rad2(0, 1), 1e-6);
  EXPECT_EQ(m->cov_rad2(1, 1), 2e-4);
  EXPECT_EQ(m->p_CinR_m, Eigen::Vector3d(0.1, -0.2, 1.8));
  f.has_elevation = false;
  EXPECT_FALSE(toMeasurement(f, cam, o)) << "a light without elevation is not a light measurement";
  f.kind = feature_t::KIND_VERTICAL_LINE;
  m = toMeasurement(f, cam, o);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->kind, slam::LandmarkKind::kVerticalLine);
  o.use_vertical_lines = false;
  EXPECT_FALSE(toMeasurement(f, cam, o));
  f.kind = 7;
  EXPECT_FALSE(toMeasurement(f, cam, SlamProcessOptions{}));
  // The sigma floor raises small variances only.
  SlamProcessOptions floor;
  floor.min_sigma_rad = 0.01;
  f.kind = feature_t::KIND_CEILING_LIGHT;
  f.has_elevation = true;
  m = toMeasurement(f, cam, floor);
  ASSERT_TRUE(m);
  EXPECT_DOUBLE_EQ(m->cov_rad2(0, 0), 1e-4);
  EXPECT_DOUBLE_EQ(m->cov_rad2(1, 1), 2e-4);
  f.covariance[0][0] = 1e-6;
  EXPECT_DOUBLE_EQ(toMeasurement(f, cam, floor)->cov_rad2(0, 0), 1e-4);
  EXPECT_EQ(toMeasurement(f, cam, floor)->cov_rad2(0, 1), 1e-6) << "off-diagonal unchanged";
}

TEST(SlamDriver, AnswersEveryFrameStampedWithItsUtimeAndSeq) {
  SlamProcessOptions o;
  o.map_every_n_frames = 3;
  SlamDriver d(o);
  const auto outs = run(d, 20);
  ASSERT_EQ(outs.size(), 20u);  // frames at 0..19 s (the one at 20 s arrives after the loop)
  int maps = 0;
  for (size_t i = 0; i < outs.size(); ++i) {
    const auto& f = outs[i];
    EXPECT_EQ(f.pose.utime, kT0 + static_cast<int64_t>(i) * 1'000'000);
    EXPECT_EQ(f.pose.input_seq, static_cast<int64_t>(i));
    EXPECT_EQ(f.pose.seq, static_cast<int64_t>(i));
    EXPECT_EQ(f.particles.utime, f.pose.utime);
    EXPECT_EQ(f.particles.input_seq, f.pose.input_seq);
    EXPECT_EQ(f.particles.num_particles, o.filter.num_particles);
    EXPECT_EQ(f.pose.num_particles, o.filter.num_particles);
    EXPECT_EQ(f.map.has_value(), i % 3 == 0) << i;
    if (f.map) {
      EXPECT_EQ(f.map->seq, maps++);
      EXPECT_EQ(f.map->utime, f.pose.utime);
      EXPECT_EQ(f.map->num_landmarks, static_cast<int32_t>(f.map->landmarks.size()));
    }
    double wsum = 0;
    for (double w : f.particles.weight) wsum += w;
    EXPECT_NEAR(wsum, 1.0, 1e-9);
  }
  // Perfect odometry and bearings: the pose follows the truth and lights get mapped.
  const Pose2 truth = hallTruthAt(outs.back().pose.utime);
  EXPECT_LT(std::hypot(outs.back().pose.x_m - truth.x_m, outs.back().pose.y_m - truth.y_m), 0.1);
  EXPECT_GT(d.stats().frames_processed, 0);
  ASSERT_NE(d.filter(), nullptr);
  EXPECT_GT(d.filter()->bestMap().size(), 4u);
  EXPECT_EQ(d.stats().pairing.dropped_no_odometry, 0);
}

TEST(SlamDriver, SameInputsAndSeedGiveIdenticalBytes) {
  SlamProcessOptions o;
  o.seed = 42;
  SlamDriver a(o), b(o);
  const auto oa = run(a, 15), ob = run(b, 15);
  ASSERT_EQ(oa.size(), ob.size());
  for (size_t i = 0; i < oa.size(); ++i) {
    EXPECT_EQ(encoded(oa[i].pose), encoded(ob[i].pose));
    EXPECT_EQ(encoded(*oa[i].map), encoded(*ob[i].map));
    EXPECT_EQ(encoded(oa[i].particles), encoded(ob[i].particles));
  }
  o.seed = 43;
  SlamDriver c(o);
  const auto oc = run(c, 15);
  EXPECT_NE(encoded(oa.back().particles), encoded(oc.back().particles)) << "the seed matters";
}

TEST(SlamDriver, FixedStartPoseSetsTheMapFrame) {
  SlamProcessOptions o;
  o.start_source = SlamProcessOptions::StartSource::kFixed;
  o.start_pose_W = Pose2{100.0, 50.0, kPi / 2};
  SlamDriver d(o);
  std::vector<FrameOutput> outs;
  for (int i = 0; i < 3; ++i) {
    d.onOdometry(hallOdometry(kT0 + i * 20'000, i));
  }
  auto r = d.onFeatures(hallFeatures(kT0, 0));
  ASSERT_EQ(r.outputs.size(), 1u);
  EXPECT_NEAR(r.outputs[0].pose.x_m, 100.0, 0.05);
  EXPECT_NEAR(r.outputs[0].pose.y_m, 50.0, 0.05);
  EXPECT_NEAR(r.outputs[0].pose.theta_rad, kPi / 2, 0.02);
}

TEST(SlamDriver, DegradedInputIsRefusedOrDroppedAndTheFilterCarriesOn) {
  SlamDriver d{SlamProcessOptions{}};
  run(d, 10);
  const Pose2 before = d.filter()->meanPose();
  // Duplicate and out-of-order odometry and frames: refused with a reason, no output.
  auto r = d.onOdometry(hallOdometry(kT0 + 10'000'000, 999));
  ASSERT_EQ(r.refused.size(), 1u);
  EXPECT_EQ(r.refused[0].channel, "ODOMETRY");
  r = d.onOdometry(hallOdometry(kT0 + 9'000'000, 999));
  ASSERT_EQ(r.refused.size(), 1u);
  EXPECT_NE(r.refused[0].reason.find("out of order"), std::string::npos);
  r = d.onFeatures(hallFeatures(kT0 + 9'000'000, 999));  // the frame at 9 s was already processed
  ASSERT_EQ(r.refused.size(), 1u);
  EXPECT_EQ(r.refused[0].channel, "OMNI_FEATURES");
  EXPECT_NE(r.refused[0].reason.find("duplicate"), std::string::npos);
  EXPECT_TRUE(r.outputs.empty());
  // A frame with broken measurements (bypassing validation): the filter rejects them, no crash.
  features_t bad = hallFeatures(kT0 + 9'950'000, 10);
  bad.features[0].azimuth_rad = std::numeric_limits<double>::quiet_NaN();
  bad.features[1].covariance[1][1] = -1.0;  // not positive definite
  r = d.onFeatures(bad);
  ASSERT_EQ(r.outputs.size(), 1u);
  EXPECT_EQ(d.stats().measurements_rejected, 2);
  EXPECT_TRUE(std::isfinite(r.outputs[0].pose.x_m));
  EXPECT_NEAR(r.outputs[0].pose.x_m, before.x_m + 0.27 * 0.95, 0.1);
  EXPECT_EQ(d.stats().pairing.duplicates, 2);
  EXPECT_EQ(d.stats().pairing.out_of_order, 1);
}

// Valid but implausible inputs: one ODOMETRY at x = 1e300 (re-based by the pairing, it would leave
// 1e282 m of rounding junk that makes every later pose NaN), theta = 1e15 rad (every step
// quantised), a frame whose camera sits 1e10 m above the robot (every light's height -1e7 m). Each
// is refused with its reason and counted, and the run goes on unharmed.
TEST(SlamDriver, ImplausibleOdometryAndCameraPositionsAreRefusedAndTheRunGoesOn) {
  SlamDriver d{SlamProcessOptions{}};
  run(d, 10);
  const int64_t processed = d.stats().frames_processed;
  odometry_t far = hallOdometry(kT0 + 10'020'000, 1000);
  far.x_m = 1e300;
  auto r = d.onOdometry(far);
  ASSERT_EQ(r.refused.size(), 1u);
  EXPECT_EQ(r.refused[0].channel, "ODOMETRY");
  EXPECT_EQ(
      r.refused[0].reason, "seq 1000 pose (1e+300 m, " + [&] {
        std::ostringstream o;
        o.precision(6);
        o << far.y_m << " m, " << far.theta_rad;
        return o.str();
      }() + " rad) outside the workspace (|x|, |y| <= 10000 m)");
  odometry_t spun = hallOdometry(kT0 + 10'040'000, 1001);
  spun.theta_rad = 1e15;
  EXPECT_EQ(d.onOdometry(spun).refused.size(), 1u);
  odometry_t edge = hallOdometry(kT0 + 10'060'000, 1002);
  edge.y_m = -10'000.0 - 1.0;
  EXPECT_EQ(d.onOdometry(edge).refused.size(), 1u);
  features_t high = hallFeatures(kT0 + 10'900'000, 1000);
  high.camera_position_m[2] = 1e10;
  r = d.onFeatures(high);
  ASSERT_EQ(r.refused.size(), 1u);
  EXPECT_EQ(r.refused[0].reason,
            "frame seq 1000: camera_position_m 1e+10 m from the robot's origin, more than "
            "plausibility.max_camera_offset_m 10");
  EXPECT_EQ(d.stats().implausible, 4);
  EXPECT_NE(d.summary().find("implausible 4;"), std::string::npos) << d.summary();
  EXPECT_EQ(d.stats().frames_processed, processed);
  // The run goes on from the last good odometry: the next frames step, and every pose is finite and
  // on the truth.
  const auto outs = run(d, 5, kT0 + 11'000'000);
  ASSERT_GE(outs.size(), 5u);
  for (const auto& o : outs) {
    ASSERT_TRUE(std::isfinite(o.pose.x_m) && std::isfinite(o.pose.y_m) && std::isfinite(o.pose.theta_rad));
    const Pose2 t = hallTruthAt(o.pose.utime);
    EXPECT_LT(std::hypot(o.pose.x_m - t.x_m, o.pose.y_m - t.y_m), 0.5) << o.pose.utime;
  }
  // A camera 10 m away is the contract's bound itself: accepted.
  SlamDriver e{SlamProcessOptions{}};
  features_t ten = hallFeatures(kT0, 0);
  ten.camera_position_m[0] = 0.0, ten.camera_position_m[1] = 0.0, ten.camera_position_m[2] = 10.0;
  e.onOdometry(hallOdometry(kT0, 0));
  EXPECT_TRUE(e.onFeatures(ten).refused.empty());
  EXPECT_EQ(e.stats().implausible, 0);
}

// Two consecutive frames stamped years ahead, mid-run, while the odometry goes on: a jump ahead of
// the frames alone is not confirmed (the next good frames would be a step back, a "restart", and the
// filter would start again at the start pose, metres off). The odometry has to jump too: the good
// frames refute the two strays, and the filter carries on.
TEST(SlamDriver, TwoStrayFramesStampedYearsAheadDoNotResetTheFilter) {
  SlamDriver d{SlamProcessOptions{}};
  ASSERT_FALSE(run(d, 10).empty());
  const int64_t years_us = int64_t{3} * 365 * 24 * 3600 * 1'000'000;
  std::vector<std::string> notes;
  for (int k = 0; k < 2; ++k) {
    const auto r = d.onFeatures(hallFeatures(kT0 + 10'200'000 + k * 100'000 + years_us, 500 + k));
    EXPECT_TRUE(r.refused.empty() && r.outputs.empty());
    notes.insert(notes.end(), r.notes.begin(), r.notes.end());
  }
  ASSERT_EQ(notes.size(), 1u) << "reported once, when the first is held";
  EXPECT_NE(notes[0].find("jumps ahead"), std::string::npos) << notes[0];
  const auto outs = run(d, 10, kT0 + 10'020'000);
  EXPECT_EQ(d.stats().pairing.restarts, 0);
  EXPECT_EQ(d.stats().filter_resets, 0);
  EXPECT_EQ(d.stats().pairing.stray_ahead, 2);
  EXPECT_EQ(d.stats().pairing.forward_jumps, 0);
  ASSERT_GE(outs.size(), 9u);
  for (const auto& o : outs) {
    const Pose2 t = hallTruthAt(o.pose.utime);
    EXPECT_LT(std::hypot(o.pose.x_m - t.x_m, o.pose.y_m - t.y_m), 0.5) << o.pose.utime;
  }
  EXPECT_GT(outs.back().map->num_landmarks, 0) << "the map was kept";
}

// A frame with more usable features than features.max_per_frame is refused whole, with its count
// and the key named, before it reaches the pairing: the filter does not step on it, and the next
// frame of ordinary size spans the odometry since the last step.
TEST(SlamDriver, AFrameWithTooManyFeaturesIsRefusedAndTheNextOneSteps) {
  SlamProcessOptions o;
  o.max_features_per_frame = 16;  // hallFeatures() gives exactly 16
  SlamDriver d{o};
  run(d, 10);
  const int64_t processed = d.stats().frames_processed;
  features_t big = hallFeatures(kT0 + 10'500'000, 10);
  big.features.push_back(big.features.front());
  big.num_features = static_cast<int32_t>(big.features.size());
  EXPECT_TRUE(d.onOdometry(hallOdometry(kT0 + 10'520'000, 600)).outputs.empty());
  EXPECT_TRUE(d.onFeatures(big).outputs.empty());
  auto r = d.onFeatures(big);  // the same again: refused for its size, not as a duplicate
  ASSERT_EQ(r.refused.size(), 1u);
  EXPECT_EQ(r.refused[0].channel, "OMNI_FEATURES");
  EXPECT_EQ(r.refused[0].reason, "frame seq 10 has 17 usable features, more than features.max_per_frame = 16");
  EXPECT_EQ(d.stats().frames_too_large, 2);
  EXPECT_EQ(d.stats().frames_processed, processed);
  EXPECT_NE(d.summary().find("too_large 2 implausible 0;"), std::string::npos) << d.summary();
  // Kinds that are off do not count: the same frame as vertical lines, with lines turned off, is
  // not too large (its features are skipped, not associated).
  SlamProcessOptions lights_only = o;
  lights_only.use_vertical_lines = false;
  SlamDriver e{lights_only};
  features_t mixed = hallFeatures(kT0, 0);
  feature_t line = mixed.features.front();
  line.kind = feature_t::KIND_VERTICAL_LINE;
  line.has_elevation = false;
  for (int i = 0; i < 40; ++i) mixed.features.push_back(line);
  mixed.num_features = static_cast<int32_t>(mixed.features.size());
  e.onOdometry(hallOdometry(kT0, 0));
  EXPECT_TRUE(e.onFeatures(mixed).refused.empty());
  EXPECT_EQ(e.stats().frames_too_large, 0);
  // The next ordinary frame steps.
  d.onOdometry(hallOdometry(kT0 + 11'000'000, 601));
  d.onOdometry(hallOdometry(kT0 + 11'020'000, 602));
  r = d.onFeatures(hallFeatures(kT0 + 11'000'000, 11));
  EXPECT_TRUE(r.refused.empty());
  EXPECT_EQ(d.stats().frames_processed, processed + 1);
}

TEST(SlamDriver, OdometryGapDropsFramesButTheNextStepSpansTheGap) {
  SlamDriver d{SlamProcessOptions{}};
  run(d, 5);  // frames 0..4 s processed, odometry to 5 s
  // Odometry silent from 5 s to 8 s (cumulative: nothing is lost), frames at 5..7 s in the gap.
  for (int i = 5; i <= 7; ++i) d.onFeatures(hallFeatures(kT0 + i * 1'000'000 + 10'000, 100 + i));
  auto r = d.onOdometry(hallOdometry(kT0 + 8'000'000, 1000));
  EXPECT_EQ(r.dropped.size(), 3u);
  EXPECT_EQ(d.stats().pairing.dropped_odometry_gap, 3);
  d.onOdometry(hallOdometry(kT0 + 8'020'000, 1001));
  r = d.onFeatures(hallFeatures(kT0 + 8'010'000, 108));
  ASSERT_EQ(r.outputs.size(), 1u);
  const Pose2 truth = hallTruthAt(kT0 + 8'010'000);
  EXPECT_NEAR(r.outputs[0].pose.x_m, truth.x_m, 0.1) << "the increment over the gap is applied whole";
}

TEST(SlamDriver, OdometryRestartingAtTheOriginIsReBasedAndTheFilterCarriesOn) {
  SlamDriver d{SlamProcessOptions{}};
  run(d, 10);  // odometry up to 10 s
  // From 10.02 s the odometry process starts again: its frame is the robot's pose at 10.02 s.
  const Pose2 origin = hallTruthAt(kT0 + 10'020'000);
  std::vector<std::string> notes;
  std::vector<FrameOutput> outs;
  int64_t seq = 0;
  for (int64_t t = kT0 + 10'020'000; t <= kT0 + 15'000'000; t += 20'000) {
    odometry_t m = hallOdometry(t, seq++);
    const Pose2 p = origin.between(hallTruthAt(t));
    m.x_m = p.x_m;
    m.y_m = p.y_m;
    m.theta_rad = p.theta_rad;
    auto r = d.onOdometry(m);
    notes.insert(notes.end(), r.notes.begin(), r.notes.end());
    if ((t - kT0 - 100'000) % 1'000'000 == 0)
      for (auto& o : d.onFeatures(hallFeatures(t - 100'000, 100 + seq)).outputs) outs.push_back(std::move(o));
  }
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("re-based"), std::string::npos) << notes[0];
  EXPECT_EQ(d.stats().pairing.odometry_jumps, 1);
  ASSERT_EQ(outs.size(), 5u);  // frames at 10..14 s
  const Pose2 truth = hallTruthAt(outs.back().pose.utime);
  // 20 ms of motion (5 mm) is lost over the jump, nothing else.
  EXPECT_LT(std::hypot(outs.back().pose.x_m - truth.x_m, outs.back().pose.y_m - truth.y_m), 0.1);
}

TEST(SlamDriver, RestartReinitialisesTheFilterAndKeepsOutputSequences) {
  SlamProcessOptions o;  // a replayed log started again: the new filter at the start pose
  o.restart.reinit_from = RestartOptions::ReinitFrom::kStartPose;
  SlamDriver d{o};
  const auto first = run(d, 10);
  ASSERT_FALSE(first.empty());
  const int64_t last_seq = first.back().pose.seq;
  std::vector<FrameOutput> second;
  int64_t oseq = 0, fseq = 0;
  std::vector<std::string> notes;
  for (int64_t t = kT0; t <= kT0 + 3'000'000; t += 20'000) {
    auto r = d.onOdometry(hallOdometry(t, oseq++));
    notes.insert(notes.end(), r.notes.begin(), r.notes.end());
    for (auto& o : r.outputs) second.push_back(std::move(o));
    if (t - 100'000 >= kT0 && (t - 100'000 - kT0) % 1'000'000 == 0) {
      auto f = d.onFeatures(hallFeatures(t - 100'000, fseq++));
      notes.insert(notes.end(), f.notes.begin(), f.notes.end());
      for (auto& o : f.outputs) second.push_back(std::move(o));
    }
  }
  // The odometry steps back first and is held (one note, not one per message held); the frame
  // stream stepping back too confirms the restart.
  ASSERT_EQ(notes.size(), 2u);
  EXPECT_NE(notes[0].find("ODOMETRY"), std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find("held"), std::string::npos) << notes[0];
  EXPECT_NE(notes[1].find("OMNI_FEATURES"), std::string::npos) << notes[1];
  EXPECT_NE(notes[1].find("restart"), std::string::npos) << notes[1];
  EXPECT_EQ(d.stats().pairing.restarts, 1);
  EXPECT_EQ(d.stats().filter_resets, 1);
  ASSERT_GE(second.size(), 2u);
  EXPECT_EQ(second.front().pose.seq, last_seq + 1) << "output seq continues across a restart";
  EXPECT_EQ(second.front().pose.utime, kT0);
  EXPECT_NEAR(second.front().pose.x_m, 6.0, 0.02) << "a new filter at the start pose";
  EXPECT_EQ(second.front().map->num_landmarks, 0);
  int64_t utime = 0;
  EXPECT_EQ(d.filterToSave(&utime), d.filter()) << "the new epoch's map is the one to save";
  EXPECT_EQ(utime, d.lastStepUtime());
}

// A restart with no frame after it still leaves the map it ended to save (not "map not saved: no
// frame was processed" after hundreds had been, and the map lost at exit).
TEST(SlamDriver, TheMapEndedByARestartIsSavedWhenNoFrameFollowsIt) {
  SlamDriver d{SlamProcessOptions{}};
  int64_t utime = -1;
  EXPECT_EQ(d.filterToSave(&utime), nullptr);
  ASSERT_FALSE(run(d, 10).empty());
  ASSERT_NE(d.filter(), nullptr);
  const int64_t last_step = d.lastStepUtime();
  const size_t landmarks = d.filter()->bestMap().size();
  ASSERT_GT(landmarks, 0u);
  // The odometry starts again from the beginning (a replayed log) and no frame comes after it: a
  // restart once the odometry held spans max_wait_s (the frame stream has gone silent).
  const int64_t wait_us = SlamProcessOptions{}.pairing.max_wait_us;
  for (int64_t k = 0; k * 20'000 <= wait_us; ++k) d.onOdometry(hallOdometry(kT0 + k * 20'000, 1000 + k));
  ASSERT_EQ(d.stats().filter_resets, 1);
  EXPECT_EQ(d.filter(), nullptr);
  const slam::FastSlam* saved = d.filterToSave(&utime);
  ASSERT_NE(saved, nullptr);
  EXPECT_EQ(utime, last_step);
  EXPECT_EQ(saved->bestMap().size(), landmarks);
}

TEST(SlamDriver, FramesWithoutOdometryAreDroppedAndCounted) {
  SlamDriver d{SlamProcessOptions{}};
  std::vector<std::string> dropped;
  for (int i = 0; i < 6; ++i) {
    auto r = d.onFeatures(hallFeatures(kT0 + i * 1'000'000, i));
    EXPECT_TRUE(r.outputs.empty());
    dropped.insert(dropped.end(), r.dropped.begin(), r.dropped.end());
  }
  EXPECT_EQ(dropped.size(), 3u);  // frames 0..2 waited more than 2 s of frame time
  auto r = d.finish();
  EXPECT_EQ(r.dropped.size(), 3u);
  EXPECT_EQ(d.stats().pairing.dropped_no_odometry, 6);
  EXPECT_EQ(d.filter(), nullptr);
  EXPECT_NE(d.summary().find("no_odometry 6"), std::string::npos) << d.summary();
}

}  // namespace

namespace {

// Features stop (the features process died) while odometry goes on: after
// odometry_only_after_us the driver publishes odometry-only poses every odometry_only_period_us
// (input_seq -1, no map, no associations); a frame older than the last prediction is dropped and
// counted; frames after it are processed again.
TEST(SlamDriver, OdometryOnlyPosesWhileFramesAreMissingThenRecovers) {
  SlamProcessOptions o;
  o.odometry_only_after_us = 3'000'000;
  o.odometry_only_period_us = 1'000'000;
  SlamDriver d(o);
  auto outs = run(d, 10);  // frames 0..9 s, odometry to 10 s
  ASSERT_EQ(outs.size(), 10u);
  for (const auto& f : outs) EXPECT_FALSE(f.odometry_only);
  // Odometry alone from 10.02 s to 20 s.
  std::vector<FrameOutput> pred;
  int64_t oseq = 10000;
  for (int64_t t = kT0 + 10'020'000; t <= kT0 + 20'000'000; t += 20'000)
    for (auto& f : d.onOdometry(hallOdometry(t, oseq++)).outputs) pred.push_back(std::move(f));
  // The last frame (9 s) arrived with the odometry of 9.1 s: predictions at 12.1, 13.1, ..., 19.1 s.
  ASSERT_EQ(pred.size(), 8u);
  for (std::size_t i = 0; i < pred.size(); ++i) {
    EXPECT_TRUE(pred[i].odometry_only);
    EXPECT_EQ(pred[i].pose.utime, kT0 + 100'000 + static_cast<int64_t>(12 + i) * 1'000'000);
    EXPECT_EQ(pred[i].pose.input_seq, -1);
    EXPECT_FALSE(pred[i].map.has_value());
    EXPECT_FALSE(pred[i].associations.has_value());
    EXPECT_EQ(pred[i].pose.seq, outs.back().pose.seq + 1 + static_cast<int64_t>(i));
    const Pose2 truth = hallTruthAt(pred[i].pose.utime);
    EXPECT_LT(std::hypot(pred[i].pose.x_m - truth.x_m, pred[i].pose.y_m - truth.y_m), 0.2);
    // The pose's ESS is that of the weights its SLAM_PARTICLES carries (the prediction keeps the
    // weights), not the last frame step's.
    double sum_w2 = 0.0;
    for (double w : pred[i].particles.weight) sum_w2 += w * w;
    EXPECT_NEAR(pred[i].pose.effective_sample_size, 1.0 / sum_w2, 1e-9);
  }
  EXPECT_EQ(d.stats().odometry_only_steps, 8);
  // A late frame from before the last prediction is dropped, not stepped backwards.
  auto late = d.onFeatures(hallFeatures(kT0 + 19'000'000, 500));
  EXPECT_TRUE(late.outputs.empty());
  ASSERT_EQ(late.dropped.size(), 1u);
  EXPECT_NE(late.dropped[0].find("odometry-only"), std::string::npos) << late.dropped[0];
  EXPECT_EQ(d.stats().dropped_behind_prediction, 1);
  // Frames come back: processed normally, with associations to the mapped lights (the first one, at
  // the time of the last prediction, is dropped; a frame seen stops the predictions).
  std::vector<FrameOutput> back;
  int64_t fseq = 600;
  for (int64_t t = kT0 + 20'020'000; t <= kT0 + 25'000'000; t += 20'000) {
    for (auto& f : d.onOdometry(hallOdometry(t, oseq++)).outputs) back.push_back(std::move(f));
    if ((t - kT0 - 100'000) % 1'000'000 == 0)
      for (auto& f : d.onFeatures(hallFeatures(t - 100'000, fseq++)).outputs) back.push_back(std::move(f));
  }
  ASSERT_GE(back.size(), 4u);
  for (const auto& f : back) {
    EXPECT_FALSE(f.odometry_only);
    ASSERT_TRUE(f.associations.has_value());
    EXPECT_EQ(f.associations->num_features, 16);
    int associated = 0;
    for (int64_t id : f.associations->landmark_id) associated += id >= 0;
    EXPECT_GT(associated, 4) << "the mapped lights are associated again";
    const Pose2 truth = hallTruthAt(f.pose.utime);
    EXPECT_LT(std::hypot(f.pose.x_m - truth.x_m, f.pose.y_m - truth.y_m), 0.2);
  }
  // Off: no prediction at all.
  SlamProcessOptions off;
  off.odometry_only_after_us = 0;
  SlamDriver d2(off);
  run(d2, 5);
  for (int64_t t = kT0 + 5'020'000; t <= kT0 + 15'000'000; t += 20'000)
    EXPECT_TRUE(d2.onOdometry(hallOdometry(t, oseq++)).outputs.empty());
}

// SLAM_ASSOCIATIONS has one entry per feature of the message: features the filter does not use
// (a kind turned off, or refused by the core: here a covariance that is not positive definite,
// which the process's own validation would have stopped earlier) are NOT_USED, the others a
// landmark id or NOT_ASSOCIATED.
TEST(SlamDriver, AssociationsCoverEveryFeatureOfTheFrame) {
  SlamProcessOptions o;
  o.use_vertical_lines = false;
  SlamDriver d(o);
  run(d, 10);
  const int64_t t = kT0 + 10'000'000;
  features_t m = hallFeatures(t, 50);
  feature_t line{};
  line.kind = feature_t::KIND_VERTICAL_LINE;
  line.covariance[0][0] = 1e-4;
  m.features.insert(m.features.begin() + 3, line);  // an unused kind in the middle
  feature_t bad = m.features[5];
  bad.covariance[0][1] = bad.covariance[1][0] = 1.0;  // not positive definite: refused by the core
  m.features.insert(m.features.begin() + 6, bad);
  m.num_features = static_cast<int32_t>(m.features.size());
  auto r = d.onFeatures(m);
  for (auto& f : d.onOdometry(hallOdometry(t + 20'000, 99999)).outputs) r.outputs.push_back(std::move(f));
  ASSERT_EQ(r.outputs.size(), 1u);
  ASSERT_TRUE(r.outputs[0].associations);
  const associations_t& a = *r.outputs[0].associations;
  EXPECT_EQ(a.utime, t);
  EXPECT_EQ(a.input_seq, 50);
  ASSERT_EQ(a.num_features, 18);
  ASSERT_EQ(a.landmark_id.size(), 18u);
  EXPECT_EQ(a.landmark_id[3], +associations_t::NOT_USED);
  EXPECT_EQ(a.landmark_id[6], +associations_t::NOT_USED);
  std::set<int64_t> ids;
  for (int i = 0; i < 18; ++i) {
    if (i == 3 || i == 6) continue;
    EXPECT_GE(a.landmark_id[i], +associations_t::NOT_ASSOCIATED);
    if (a.landmark_id[i] >= 0) {
      EXPECT_TRUE(ids.insert(a.landmark_id[i]).second) << "one landmark per feature";
    }
  }
  EXPECT_GT(ids.size(), 4u);
  // Every associated id is in the map of the best particle.
  const auto map = d.filter()->bestMap();
  for (int64_t id : ids)
    EXPECT_TRUE(std::any_of(map.begin(), map.end(), [&](const slam::Landmark& L) { return int64_t(L.id) == id; }));
}

// Localisation only from a saved map: the pose follows the truth, the map is exactly the prior.
TEST(SlamDriver, LocalisationOnlyFromAPriorMap) {
  std::vector<slam::Landmark> prior;
  for (const auto& p : slam::scenarios::hallLights()) {
    slam::Landmark L;
    L.id = 1000 + prior.size();
    L.p_LinW_m = p;
    L.cov_LinW_m2 = Eigen::Matrix3d::Identity() * 1e-3;
    L.counter = 20;
    prior.push_back(L);
  }
  SlamProcessOptions o;
  o.localisation_only = true;
  o.load_map_path = "prior.yaml";  // only its presence is checked here; main.cpp reads the file
  o.start_source = SlamProcessOptions::StartSource::kFixed;
  o.start_pose_W = hallTruthAt(kT0);
  SlamDriver d(o, prior);
  const auto outs = run(d, 15);
  ASSERT_EQ(outs.size(), 15u);
  for (const auto& f : outs) {
    const Pose2 truth = hallTruthAt(f.pose.utime);
    EXPECT_LT(std::hypot(f.pose.x_m - truth.x_m, f.pose.y_m - truth.y_m), 0.1);
    ASSERT_TRUE(f.associations);
    int associated = 0;
    for (int64_t id : f.associations->landmark_id) associated += id >= 1000;
    EXPECT_GE(associated, 10);
  }
  const auto map = d.filter()->bestMap();
  ASSERT_EQ(map.size(), prior.size());
  for (std::size_t i = 0; i < map.size(); ++i) {
    EXPECT_EQ(map[i].id, prior[i].id);
    EXPECT_EQ(map[i].p_LinW_m, prior[i].p_LinW_m);
    EXPECT_EQ(map[i].counter, 20);
  }
  EXPECT_EQ(d.filter()->bestCandidateCount(), 0u);
  // Localisation without a map is refused at construction.
  SlamProcessOptions bad;
  bad.localisation_only = true;
  bad.load_map_path = "x.yaml";
  EXPECT_THROW(SlamDriver(bad, {}), std::invalid_argument);
  bad.load_map_path.clear();
  EXPECT_NE(bad.validate().find("load_path"), std::string::npos) << bad.validate();
}

}  // namespace

namespace {

// A features stream that lags 5 s behind the odometry but keeps arriving (a loaded machine, or its
// recording replayed) is not a dead one: no odometry-only step, every frame processed.
TEST(SlamDriver, LaggingButAliveFeaturesNeverTriggerPredictions) {
  SlamProcessOptions o;
  o.odometry_only_after_us = 3'000'000;
  SlamDriver d(o);
  int64_t oseq = 0, fseq = 0, outputs = 0;
  for (int64_t t = kT0; t <= kT0 + 30'000'000; t += 20'000) {
    for (auto& f : d.onOdometry(hallOdometry(t, oseq++)).outputs) {
      EXPECT_FALSE(f.odometry_only) << "at odometry time " << (t - kT0) * 1e-6;
      ++outputs;
    }
    const int64_t tf = t - 5'000'000;  // the frame taken 5 s ago arrives now
    if (tf >= kT0 && (tf - kT0) % 1'000'000 == 0)
      for (auto& f : d.onFeatures(hallFeatures(tf, fseq++)).outputs) {
        EXPECT_FALSE(f.odometry_only);
        ++outputs;
      }
  }
  EXPECT_EQ(outputs, 26);  // frames at 0..25 s
  EXPECT_EQ(d.stats().odometry_only_steps, 0);
  EXPECT_EQ(d.stats().dropped_behind_prediction, 0);
}

}  // namespace
