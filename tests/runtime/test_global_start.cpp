// The localising phase of a run with no start pose (common/runtime/.../global_start.h) alone and
// inside the step driver (start_pose.source unknown): no pose before the fix, the fix near the truth,
// the filter tracking from it; the half-turn symmetric sports hall never localised; config errors.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "omnislam/core/angles.h"
#include "omnislam/lcmio/validate.h"
#include "omnislam/runtime/global_start.h"
#include "omnislam/runtime/slam_driver.h"
#include "slam_inputs.h"

using namespace omnislam;
using namespace omnislam::runtime;
using namespace omnislam::testing;

namespace {

/// The odometry frame O is not the map frame: the robot's pose in O is kWinO * T_WtoR (the odometry
/// starts elsewhere and heads elsewhere).
const Pose2 kWinO{-3.0, 7.0, 1.0};
Pose2 odomOf(const Pose2& truth_W) { return kWinO.compose(truth_W); }

SlamProcessOptions unknownStart() {
  SlamProcessOptions o;
  o.start_source = SlamProcessOptions::StartSource::kUnknown;
  o.load_map_path = "map.yaml";  // read by the process, not by the driver: the map is given to it
  return o;
}

/// The hall drive (exact odometry in O, exact bearings of `lights`) for `seconds`, frames 1 Hz.
struct DriveRun {
  std::vector<FrameOutput> outputs;
  std::vector<slam_localisation_t> localisation;
  std::vector<std::string> notes;
};
DriveRun drive(SlamDriver& d, int seconds, const std::vector<Eigen::Vector3d>& lights) {
  DriveRun run;
  int64_t oseq = 0, fseq = 0;
  const auto take = [&](DriverResult r) {
    for (auto& o : r.outputs) run.outputs.push_back(std::move(o));
    for (auto& l : r.localisation) run.localisation.push_back(std::move(l));
    for (auto& n : r.notes) run.notes.push_back(std::move(n));
  };
  for (int64_t t = kT0; t <= kT0 + seconds * 1'000'000LL; t += 20'000) {
    take(d.onOdometry(odometryAt(t, oseq++, odomOf(hallTruthAt(t)), 0.27)));
    if (t - 100'000 >= kT0 && (t - 100'000 - kT0) % 1'000'000 == 0)
      take(d.onFeatures(lightFeatures(t - 100'000, fseq++, hallTruthAt(t - 100'000), lights)));
  }
  return run;
}

double headingErrorDeg(double a_rad, double b_rad) { return std::abs(wrapAngle(a_rad - b_rad)) * 180.0 / kPi; }

}  // namespace

TEST(GlobalStart, LocalisesOnceThenTracksAndRestartsFromNothing) {
  const auto lights = hallLightsPlus17th(true);
  const SlamProcessOptions o = unknownStart();
  GlobalStart g(o.localisation, o.filter, exactMapOf(lights));
  EXPECT_EQ(g.phase(), GlobalStart::Phase::kLocalising);
  std::optional<GlobalStart::Fix> fix;
  int64_t frame = 0, fix_frame = -1;
  for (; frame < 30 && !fix; ++frame) {
    const int64_t t = kT0 + frame * 1'000'000;
    const Frame f = toFrame(lightFeatures(t, frame, hallTruthAt(t), lights), o);
    fix = g.onFrame(odomOf(hallTruthAt(t)), f.z);
    if (fix) fix_frame = frame;
    else EXPECT_NE(g.status().state, slam::LocalisationState::kLocalised);
  }
  ASSERT_TRUE(fix) << "not localised in 30 frames (8 m)";
  const Pose2 truth = hallTruthAt(kT0 + fix_frame * 1'000'000);
  EXPECT_LT(std::hypot(fix->pose_W.x_m - truth.x_m, fix->pose_W.y_m - truth.y_m), 0.3);
  EXPECT_LT(headingErrorDeg(fix->pose_W.theta_rad, truth.theta_rad), 2.0);
  EXPECT_GT(fix->cov(0, 0), 0.0);
  EXPECT_EQ(g.phase(), GlobalStart::Phase::kTracking);
  EXPECT_EQ(g.status().state, slam::LocalisationState::kLocalised);
  EXPECT_EQ(g.fixes(), 1);
  EXPECT_EQ(g.frames(), fix_frame + 1);
  EXPECT_THROW(g.onFrame(odomOf(truth), {}), std::logic_error) << "tracking takes no frame";
  g.restart();
  EXPECT_EQ(g.phase(), GlobalStart::Phase::kLocalising);
  EXPECT_EQ(g.status().state, slam::LocalisationState::kSearching);
  EXPECT_EQ(g.status().frames, 0);
}

TEST(GlobalStart, RefusesAMapWithoutLightsAndInvalidOptions) {
  const SlamProcessOptions o = unknownStart();
  std::vector<slam::Landmark> lines = exactMapOf(hallLightsPlus17th(false));
  for (auto& l : lines) l.kind = slam::LandmarkKind::kVerticalLine;
  EXPECT_THROW(GlobalStart(o.localisation, o.filter, lines), std::invalid_argument);
  slam::GlobalLocalisationOptions bad = o.localisation;
  bad.min_matched = bad.max_seed_bearings + 1;
  EXPECT_THROW(GlobalStart(bad, o.filter, exactMapOf(hallLightsPlus17th(false))), std::invalid_argument);
}

TEST(GlobalStart, MessageCarriesTheStatusAndValidates) {
  slam::LocalisationStatus s;
  s.state = slam::LocalisationState::kAmbiguous;
  s.num_hypotheses = 2;
  s.num_tracked = 3;
  s.frames = 7;
  for (double ll : {-4.0, -4.5}) {
    slam::PoseHypothesis h;
    h.pose_W = Pose2{1.0, 2.0, 0.5};
    h.cov = Eigen::Matrix3d::Identity() * 0.01;
    h.cov(0, 1) = h.cov(1, 0) = 0.002;
    h.log_likelihood = ll;
    h.frames_explained = 5;
    h.travel_m = 1.25;
    s.best.push_back(h);
  }
  const slam_localisation_t m = toLocalisationMessage(s, kT0, 4, 9);
  EXPECT_FALSE(lcmio::validate(m)) << *lcmio::validate(m);
  EXPECT_EQ(m.utime, kT0);
  EXPECT_EQ(m.seq, 4);
  EXPECT_EQ(m.input_seq, 9);
  EXPECT_EQ(m.state, slam_localisation_t::STATE_AMBIGUOUS);
  EXPECT_EQ(m.num_hypotheses, 2);
  EXPECT_EQ(m.num_tracked, 3);
  EXPECT_EQ(m.num_frames, 7);
  ASSERT_EQ(m.num_reported, 2);
  EXPECT_EQ(m.relative_log_likelihood[0], 0.0);
  EXPECT_EQ(m.relative_log_likelihood[1], -0.5);
  EXPECT_EQ(m.covariance[1][1], 0.002) << "row-major";
  EXPECT_EQ(m.covariance[1][4], 0.01);
  EXPECT_EQ(m.frames_explained[1], 5);
  EXPECT_EQ(m.travel_m[0], 1.25);
}

// In the asymmetric hall: every frame before the fix has a SLAM_LOCALISATION and no pose; the fix
// is near the truth; from the next frame the filter tracks in the map frame, near the truth.
TEST(SlamDriverUnknownStart, NoPoseBeforeTheFixThenTracksInTheMapFrame) {
  const auto lights = hallLightsPlus17th(true);
  SlamDriver d(unknownStart(), exactMapOf(lights));
  const DriveRun run = drive(d, 25, lights);
  ASSERT_FALSE(run.localisation.empty());
  const slam_localisation_t& last = run.localisation.back();
  ASSERT_EQ(last.state, slam_localisation_t::STATE_LOCALISED) << "not localised in 25 frames";
  for (std::size_t k = 0; k + 1 < run.localisation.size(); ++k) {
    EXPECT_NE(run.localisation[k].state, slam_localisation_t::STATE_LOCALISED);
    EXPECT_EQ(run.localisation[k].seq, static_cast<int64_t>(k));
    EXPECT_EQ(run.localisation[k].input_seq, static_cast<int64_t>(k));
    EXPECT_FALSE(lcmio::validate(run.localisation[k]));
  }
  const Pose2 at_fix = hallTruthAt(last.utime);
  EXPECT_LT(std::hypot(last.x_m[0] - at_fix.x_m, last.y_m[0] - at_fix.y_m), 0.3);
  EXPECT_LT(headingErrorDeg(last.theta_rad[0], at_fix.theta_rad), 2.0);
  ASSERT_FALSE(run.outputs.empty());
  EXPECT_EQ(run.outputs.front().pose.input_seq, last.input_seq + 1) << "poses start with the frame after the fix";
  EXPECT_EQ(run.outputs.front().pose.seq, 0);
  for (const FrameOutput& out : run.outputs) {
    const Pose2 truth = hallTruthAt(out.pose.utime);
    EXPECT_LT(std::hypot(out.pose.x_m - truth.x_m, out.pose.y_m - truth.y_m), 0.3) << out.pose.input_seq;
    EXPECT_LT(headingErrorDeg(out.pose.theta_rad, truth.theta_rad), 2.0) << out.pose.input_seq;
  }
  EXPECT_EQ(d.stats().localisation_fixes, 1);
  EXPECT_EQ(d.stats().frames_localising, static_cast<int64_t>(run.localisation.size()));
  EXPECT_NE(d.summary().find("localisation: frames"), std::string::npos);
  bool noted = false;
  for (const auto& n : run.notes) noted = noted || n.find("localised after") != std::string::npos;
  EXPECT_TRUE(noted);
}

// The sports hall as it is (16 lights, half-turn symmetric): never localised, so never a pose.
TEST(SlamDriverUnknownStart, SymmetricHallIsNeverLocalisedAndPublishesNoPose) {
  const auto lights = hallLightsPlus17th(false);
  SlamDriver d(unknownStart(), exactMapOf(lights));
  const DriveRun run = drive(d, 40, lights);
  EXPECT_TRUE(run.outputs.empty());
  ASSERT_EQ(run.localisation.size(), 40u);
  int ambiguous = 0;
  for (const auto& l : run.localisation) {
    EXPECT_NE(l.state, slam_localisation_t::STATE_LOCALISED);
    ambiguous += l.state == slam_localisation_t::STATE_AMBIGUOUS;
  }
  EXPECT_GT(ambiguous, 20) << "the two half-turned poses both explain the lights";
  EXPECT_EQ(d.filter(), nullptr);
}

TEST(SlamDriverUnknownStart, SameInputsGiveIdenticalBytes) {
  const auto lights = hallLightsPlus17th(true);
  SlamDriver a(unknownStart(), exactMapOf(lights)), b(unknownStart(), exactMapOf(lights));
  const DriveRun ra = drive(a, 12, lights), rb = drive(b, 12, lights);
  ASSERT_EQ(ra.localisation.size(), rb.localisation.size());
  for (std::size_t k = 0; k < ra.localisation.size(); ++k)
    EXPECT_EQ(encoded(ra.localisation[k]), encoded(rb.localisation[k]));
  ASSERT_EQ(ra.outputs.size(), rb.outputs.size());
  for (std::size_t k = 0; k < ra.outputs.size(); ++k)
    EXPECT_EQ(encoded(ra.outputs[k].pose), encoded(rb.outputs[k].pose));
}

TEST(SlamDriverUnknownStart, NeedsAMap) {
  SlamProcessOptions o = unknownStart();
  EXPECT_THROW(SlamDriver(o, {}), std::invalid_argument);
  o.load_map_path.clear();
  EXPECT_NE(o.validate().find("start_pose.source"), std::string::npos) << o.validate();
}
