// omnislam-smooth end to end on a synthetic recorded run with known answers: a robot circling five
// vertical-line landmarks (initial map 0.36 m off), drifting odometry, a filter estimate 0.3 m off; the smoothed copy
// of the log must be near the truth, keep every other channel, and refuse or count bad input; the incremental mode must
// publish causal poses (the same whether or not the run goes on).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <random>

#include <Eigen/Core>

#include "omnislam/associations_t.hpp"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "proc_util.h"
#include "slam_log.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

const std::vector<Eigen::Vector2d> kLandmarks = {{3.0, 0.5}, {-3.0, 1.0}, {0.5, 3.2}, {-0.5, -3.0}, {2.5, -2.5}};
constexpr double kSigmaRad = 0.0175;  // 1 deg

double truthX(double t) { return 2.0 * std::cos(0.1 * t); }
double truthY(double t) { return 2.0 * std::sin(0.1 * t); }
double truthTheta(double t) { return std::remainder(0.1 * t + M_PI / 2, 2 * M_PI); }

/// The five landmarks as a map: ids id0 + j, each moved by offset_m.
map_t landmarkMap(int64_t id0, const Eigen::Vector2d& offset_m) {
  std::vector<std::pair<int64_t, Eigen::Vector2d>> pts;
  for (size_t j = 0; j < kLandmarks.size(); ++j)
    pts.emplace_back(id0 + static_cast<int64_t>(j), kLandmarks[j] + offset_m);
  return t::makeLineMap(pts);
}

/// 60 s: ODOMETRY at 20 Hz (heading drifting 0.01 rad/s), 2 Hz frames of all five landmarks with
/// SLAM_POSE up to 0.3 m off the truth, SLAM_ASSOCIATIONS (ids 100 + j), labels (ids j), a SLAM_MAP 0.3 m
/// off, GROUND_TRUTH_POSE; with `garbage`, one undecodable ODOMETRY event as well. `last_step`
/// (<= 1200) ends the run early: the same events up to then. With `repeat_odometry`, one
/// ODOMETRY message is written twice.
void writeRun(const std::string& path, bool garbage, bool with_slam_pose = true, int last_step = 1200,
              bool repeat_odometry = false) {
  lcmio::LogWriter w(path);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n01(0.0, 1.0);
  const int64_t t0 = 1'000'000'000;
  double ox = 0, oy = 0, oth = 0;  // odometry integrated with a heading bias
  int64_t seq = 0, fseq = 0;
  map_t truth_map = landmarkMap(0, Eigen::Vector2d::Zero());
  truth_map.utime = t0;
  w.write(t0, channels::kGroundTruthMap, truth_map);
  for (int k = 0; k <= last_step; ++k) {
    const double t = k * 0.05;
    const int64_t u = t0 + static_cast<int64_t>(std::llround(t * 1e6));
    if (k > 0) {
      const double v = 0.2, om = 0.1 + 0.01;
      ox += v * 0.05 * std::cos(oth);
      oy += v * 0.05 * std::sin(oth);
      oth = std::remainder(oth + om * 0.05, 2 * M_PI);
    }
    odometry_t o{};
    o.utime = u, o.seq = seq++, o.x_m = ox, o.y_m = oy, o.theta_rad = oth, o.v_mps = 0.2, o.omega_radps = 0.11;
    w.write(u, channels::kOdometry, o);
    if (repeat_odometry && k == 600) w.write(u, channels::kOdometry, o);  // the same utime again
    if (garbage && k == 600) {
      const uint8_t junk[5] = {1, 2, 3, 4, 5};
      w.write(u, channels::kOdometry, junk, 5);
    }
    if (k % 10 != 0) continue;
    const double x = truthX(t), y = truthY(t), th = truthTheta(t);
    features_t f{};
    f.utime = u, f.seq = fseq, f.image_seq = fseq, f.detector = "synthetic";
    associations_t a{};
    a.utime = u, a.seq = fseq, a.input_seq = fseq;
    feature_labels_t lab{};
    lab.utime = u, lab.seq = fseq, lab.features_seq = fseq;
    for (size_t j = 0; j < kLandmarks.size(); ++j) {
      feature_t ft{};
      ft.kind = feature_t::KIND_VERTICAL_LINE;
      ft.azimuth_rad = std::remainder(
          std::atan2(kLandmarks[j].y() - y, kLandmarks[j].x() - x) - th + kSigmaRad * n01(rng), 2 * M_PI);
      ft.covariance[0][0] = kSigmaRad * kSigmaRad;
      f.features.push_back(ft);
      a.landmark_id.push_back(100 + static_cast<int64_t>(j));
      lab.landmark_id.push_back(static_cast<int64_t>(j));
      lab.source_code.push_back(0);
    }
    f.num_features = a.num_features = lab.num_features = static_cast<int32_t>(kLandmarks.size());
    w.write(u, channels::kOmniFeatures, f);
    w.write(u, channels::kGroundTruthFeatureLabels, lab);
    w.write(u, channels::kGroundTruthPose, t::makePose(u, x, y, th));
    if (with_slam_pose) {
      // Starts at the truth (the known start pose, which the smoother's prior holds), then drifts off.
      pose_t p =
          t::makePose(u, x + 0.3 * std::sin(0.3 * t), y + 0.3 * std::sin(0.2 * t), th + 0.05 * std::sin(0.1 * t));
      p.input_seq = fseq;
      w.write(u, channels::kSlamPose, p);
      w.write(u, channels::kSlamAssociations, a);
      map_t m = landmarkMap(100, Eigen::Vector2d(0.3, -0.2));
      m.utime = u, m.seq = fseq, m.input_seq = fseq;
      w.write(u, channels::kSlamMap, m);
    }
    ++fseq;
  }
}

double rmseToTruth(const std::vector<pose_t>& est) {
  double s = 0;
  for (const auto& p : est) {
    const double t = static_cast<double>(p.utime - 1'000'000'000) * 1e-6;
    s += std::pow(p.x_m - truthX(t), 2) + std::pow(p.y_m - truthY(t), 2);
  }
  return std::sqrt(s / static_cast<double>(est.size()));
}

/// Every landmark of `map` has an id in [id0, id0 + 5) and lies within 0.1 m of that true landmark.
void expectLandmarksNearTruth(const map_t& map, int64_t id0) {
  for (const auto& l : map.landmarks) {
    const int64_t j = l.id - id0;
    ASSERT_TRUE(j >= 0 && j < static_cast<int64_t>(kLandmarks.size())) << "landmark id " << l.id;
    const Eigen::Vector2d& truth = kLandmarks[static_cast<size_t>(j)];
    EXPECT_LT(std::hypot(l.position_m[0] - truth.x(), l.position_m[1] - truth.y()), 0.1) << "landmark " << l.id;
  }
}

t::RunResult smooth(const std::string& in, const std::string& out, const std::vector<std::string>& extra) {
  std::vector<std::string> argv{t::binPath("omnislam-smooth"),           in, "--out", out, "--config",
                                t::sourcePath("config/slam/mrclam.yaml")};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return t::run(argv, 60.0);
}

TEST(Smooth, BringsTheFilterEstimateToTheTruthAndKeepsTheOtherChannels) {
  t::TempDir dir;
  const std::string in = dir.file("in.lcm"), out = dir.file("out.lcm");
  writeRun(in, false);
  const auto r = smooth(in, out, {});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("121 poses, 120 odometry and 605 bearing factors"), std::string::npos) << r.output;

  const auto before = lcmio::readChannel<pose_t>(in, channels::kSlamPose);
  const auto after = lcmio::readChannel<pose_t>(out, channels::kSlamPose);
  ASSERT_EQ(after.size(), before.size());
  for (size_t i = 0; i < after.size(); ++i) EXPECT_EQ(after[i].utime, before[i].utime);
  const double e_before = rmseToTruth(before), e_after = rmseToTruth(after);
  EXPECT_GT(e_before, 0.15);
  EXPECT_LT(e_after, 0.05) << "filter " << e_before;

  const auto maps = lcmio::readChannel<map_t>(out, channels::kSlamMap);
  ASSERT_EQ(maps.size(), 1u) << "one final map";
  ASSERT_EQ(maps[0].num_landmarks, 5);
  ASSERT_NO_FATAL_FAILURE(expectLandmarksNearTruth(maps[0], 100));
  for (const auto& l : maps[0].landmarks) EXPECT_EQ(l.times_detected, 121);
  // Everything else is copied; the filter's particles are not.
  for (const char* ch : {channels::kOdometry, channels::kOmniFeatures, channels::kGroundTruthPose,
                         channels::kGroundTruthFeatureLabels, channels::kSlamAssociations}) {
    size_t n_in = 0, n_out = 0;
    lcmio::forEachEvent(in, [&](const lcmio::LogEvent& ev) { n_in += ev.channel == ch; });
    lcmio::forEachEvent(out, [&](const lcmio::LogEvent& ev) { n_out += ev.channel == ch; });
    EXPECT_EQ(n_out, n_in) << ch;
  }
  // omnislam-eval reads the copy.
  const auto ev = t::run({t::binPath("omnislam-eval"), out, "--planar", "--json", "--no-tum"}, 60.0);
  ASSERT_EQ(ev.exit_code, 0) << ev.output;
  EXPECT_LT(t::jsonNumber(ev.output, "ate_rmse_m"), 0.05) << ev.output;
  EXPECT_EQ(t::jsonNumber(ev.output, "landmarks_matched"), 5) << ev.output;
}

TEST(Smooth, LabelsGiveTheTruthIdsAndDropTheFilterAssociations) {
  t::TempDir dir;
  const std::string in = dir.file("in.lcm"), out = dir.file("out.lcm");
  writeRun(in, false);
  const auto r = smooth(in, out, {"--associations", "labels", "--initial-from-odometry"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_LT(rmseToTruth(lcmio::readChannel<pose_t>(out, channels::kSlamPose)), 0.05);
  const auto maps = lcmio::readChannel<map_t>(out, channels::kSlamMap);
  ASSERT_EQ(maps.size(), 1u);
  ASSERT_EQ(maps[0].num_landmarks, 5);
  ASSERT_NO_FATAL_FAILURE(expectLandmarksNearTruth(maps[0], 0));
  EXPECT_TRUE(lcmio::readChannel<associations_t>(out, channels::kSlamAssociations).empty());
}

TEST(Smooth, IncrementalPublishesEachPoseFromItsOwnFramesSolve) {
  t::TempDir dir;
  const std::string in = dir.file("in.lcm"), out = dir.file("out.lcm");
  writeRun(in, false);
  const auto r = smooth(in, out, {"--associations", "labels", "--incremental"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("121 poses, 120 odometry and 605 bearing factors"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("121 solve(s)"), std::string::npos) << r.output;
  const auto online = lcmio::readChannel<pose_t>(out, channels::kSlamPose);
  ASSERT_EQ(online.size(), 121u);
  EXPECT_LT(rmseToTruth(online), 0.05);
  const auto maps = lcmio::readChannel<map_t>(out, channels::kSlamMap);
  ASSERT_EQ(maps.size(), 1u);
  ASSERT_EQ(maps[0].num_landmarks, 5);
  ASSERT_NO_FATAL_FAILURE(expectLandmarksNearTruth(maps[0], 0));

  // Causal: the first 61 frames of a run that ends there get exactly the same poses.
  const std::string half = dir.file("half.lcm"), half_out = dir.file("half_out.lcm");
  writeRun(half, false, true, 600);
  ASSERT_EQ(smooth(half, half_out, {"--associations", "labels", "--incremental"}).exit_code, 0);
  const auto early = lcmio::readChannel<pose_t>(half_out, channels::kSlamPose);
  ASSERT_EQ(early.size(), 61u);
  for (size_t i = 0; i < early.size(); ++i) {
    EXPECT_EQ(early[i].utime, online[i].utime);
    EXPECT_EQ(early[i].x_m, online[i].x_m) << i;
    EXPECT_EQ(early[i].y_m, online[i].y_m) << i;
    EXPECT_EQ(early[i].theta_rad, online[i].theta_rad) << i;
  }
  // The batch solve of the whole run does use later frames: it differs from the causal poses.
  const std::string batch_out = dir.file("batch.lcm");
  ASSERT_EQ(smooth(in, batch_out, {"--associations", "labels", "--initial-from-odometry"}).exit_code, 0);
  const auto batch = lcmio::readChannel<pose_t>(batch_out, channels::kSlamPose);
  ASSERT_EQ(batch.size(), online.size());
  EXPECT_NE(batch[60].x_m, online[60].x_m);

  const auto bad = smooth(in, out, {"--incremental", "--min-rays", "1"});
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("min-rays"), std::string::npos) << bad.output;
}

TEST(Smooth, CountsAnUndecodableMessageAndRefusesBadFlagsAndLogs) {
  t::TempDir dir;
  const std::string in = dir.file("in.lcm"), out = dir.file("out.lcm");
  writeRun(in, true);
  const auto r = smooth(in, out, {});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("skipped ODOMETRY: undecodable (shorter than a fingerprint) (1)"), std::string::npos)
      << r.output;

  // Inputs are kept by utime: a repeated message would silently replace the first. It is counted.
  const std::string repeated = dir.file("repeated.lcm");
  writeRun(repeated, false, true, 1200, true);
  const auto rr = smooth(repeated, out, {});
  ASSERT_EQ(rr.exit_code, 0) << rr.output;
  EXPECT_NE(rr.output.find("skipped ODOMETRY: utime duplicated, out of order or jumping (lcmio::UtimeOrder) (1)"),
            std::string::npos)
      << rr.output;

  EXPECT_EQ(smooth(in, out, {"--associations", "oracle"}).exit_code, 2);
  const auto bad_key = smooth(in, out, {"--set", "filter.motion.no_such_key=1"});
  EXPECT_EQ(bad_key.exit_code, 2) << bad_key.output;
  EXPECT_NE(bad_key.output.find("no_such_key"), std::string::npos) << bad_key.output;

  const std::string no_slam = dir.file("no_slam.lcm");
  writeRun(no_slam, false, false);
  const auto r2 = smooth(no_slam, out, {});
  EXPECT_EQ(r2.exit_code, 2) << r2.output;  // as omnislam-eval: an unusable input log
  EXPECT_NE(r2.output.find("no SLAM_POSE message"), std::string::npos) << r2.output;

  // --out naming the input emptied it before it was read, and exited 0; it is refused, untouched.
  const auto size = std::filesystem::file_size(in);
  const auto same = smooth(in, in, {});
  EXPECT_EQ(same.exit_code, 2) << same.output;
  EXPECT_NE(same.output.find("--out: '" + in + "' is the input log"), std::string::npos) << same.output;
  EXPECT_EQ(std::filesystem::file_size(in), size);
  // The output is written whole or not at all: no OUT.partial is left after a run that finished.
  EXPECT_FALSE(std::filesystem::exists(out + ".partial"));
}

/// Copies the events of `in` into `out` (log time kept), each through `keep` (false: left out).
void copyLog(const std::string& in, lcmio::LogWriter& out, const std::function<bool(const lcmio::LogEvent&)>& keep) {
  lcmio::forEachEvent(in, [&](const lcmio::LogEvent& ev) {
    if (keep(ev)) out.write(ev.log_utime, ev.channel, ev.data.data(), static_cast<int32_t>(ev.data.size()));
  });
}

// Two runs in one log (the second starts again at the first one's utimes): lcmio::UtimeOrder accepts
// the new timeline; the restart and every message it replaces are reported, not merged in silence.
TEST(Smooth, ARestartedTimelineIsReported) {
  t::TempDir dir;
  const std::string run = dir.file("run.lcm"), in = dir.file("in.lcm"), out = dir.file("out.lcm");
  writeRun(run, false, true, 400);
  {
    lcmio::LogWriter w(in);
    copyLog(run, w, [](const lcmio::LogEvent&) { return true; });
    copyLog(run, w, [](const lcmio::LogEvent&) { return true; });
  }
  const auto r = smooth(in, out, {});
  EXPECT_NE(r.output.find("warning: SLAM_POSE: 1 new timeline(s) accepted"), std::string::npos) << r.output;
  EXPECT_NE(
      r.output.find("SLAM_POSE: utime already read before its timeline restarted, replaced by this later message"),
      std::string::npos)
      << r.output;
}

// One SLAM_POSE at x = 1e300 makes the cost infinite: the old hand-written smoother accepted no step
// and called that converged, and the tool wrote landmarks at 1e298. The back end's solver
// (smoothing::solve) fails on it, and the tool stops with that reason and writes nothing (it also
// refuses any non-finite result itself).
TEST(Smooth, ADivergedSolveIsAnError) {
  t::TempDir dir;
  const std::string run = dir.file("run.lcm"), in = dir.file("in.lcm"), out = dir.file("out.lcm");
  writeRun(run, false, true, 400);
  {
    lcmio::LogWriter w(in);
    const int64_t u = 1'000'000'000 + 5'250'000;  // between two frames, inside the odometry
    bool written = false;
    copyLog(run, w, [&](const lcmio::LogEvent& ev) {
      if (!written && ev.log_utime > u) w.write(u, channels::kSlamPose, t::makePose(u, 1e300, 1e300, 0));
      written = written || ev.log_utime > u;
      return true;
    });
  }
  const auto r = smooth(in, out, {});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("smoother: solver: the solver failed"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out));
}

// Two ODOMETRY 1000 s apart: the second is refused as a forward jump, and the refusal of the log
// ("fewer than two") says so.
TEST(Smooth, ARefusalNamesTheSkippedInput) {
  t::TempDir dir;
  const std::string in = dir.file("in.lcm"), out = dir.file("out.lcm");
  {
    lcmio::LogWriter w(in);
    for (int k = 0; k < 2; ++k) {
      odometry_t o{};
      o.utime = 1'000'000'000 + k * 1'000'000'000LL, o.seq = k, o.x_m = k;
      w.write(o.utime, channels::kOdometry, o);
      w.write(o.utime, channels::kSlamPose, t::makePose(o.utime, k, 0, 0));
    }
  }
  const auto r = smooth(in, out, {});
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(
      r.output.find("fewer than two ODOMETRY messages (skipped: ODOMETRY: utime duplicated, out of order or jumping"),
      std::string::npos)
      << r.output;
}

// No ODOMETRY between 10 s and 20 s: the 19 frames inside that gap get no odometry factor (the SLAM
// config's pairing.max_odometry_gap_s, 1.5 s for mrclam.yaml) and are counted; --incremental refuses.
TEST(Smooth, AnOdometryGapIsNotBridged) {
  t::TempDir dir;
  const std::string run = dir.file("run.lcm"), in = dir.file("in.lcm"), out = dir.file("out.lcm");
  writeRun(run, false);
  {
    lcmio::LogWriter w(in);
    copyLog(run, w, [](const lcmio::LogEvent& ev) {
      const int64_t u = ev.log_utime - 1'000'000'000;
      return ev.channel != channels::kOdometry || u <= 10'000'000 || u >= 20'000'000;
    });
  }
  const auto r = smooth(in, out, {});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("121 poses, 100 odometry"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("19 frames without odometry (19 across a gap over 1.5 s)"), std::string::npos) << r.output;
  const auto inc = smooth(in, out, {"--associations", "labels", "--incremental"});
  EXPECT_EQ(inc.exit_code, 2) << inc.output;
  EXPECT_NE(inc.output.find("19 frame(s) without (19 of them across a gap"), std::string::npos) << inc.output;
}

// --incremental re-solves the whole problem at every frame (quadratic): it reports its progress.
TEST(Smooth, IncrementalReportsItsProgress) {
  t::TempDir dir;
  const std::string in = dir.file("in.lcm"), out = dir.file("out.lcm");
  writeRun(in, false, true, 400);  // 41 frames
  const auto r = smooth(in, out, {"--associations", "labels", "--incremental"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  size_t lines = 0;
  for (size_t at = r.output.find("incremental: frame "); at != std::string::npos;
       at = r.output.find("incremental: frame ", at + 1))
    ++lines;
  EXPECT_GE(lines, 9u) << r.output;
  EXPECT_LE(lines, 10u) << r.output;
  EXPECT_NE(r.output.find("incremental: frame 5 of 41 (12 %)"), std::string::npos) << r.output;
}

}  // namespace
