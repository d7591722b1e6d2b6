// omnislam-eval on logs with known answers: a SLAM trajectory offset from the truth by a fixed
// translation, a map with one displaced landmark, a duplicate and a ghost; raw, --align, --truth
// from a second log, the TUM files, bad input, and runs the SLAM output covers only in part.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>

#include "omnislam/associations_t.hpp"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/map_t.hpp"
#include "omnislam/pose_t.hpp"
#include "eval_json.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/log_writer.h"
#include "proc_util.h"
#include "slam_log.h"

using namespace omnislam;
namespace t = omnislam::testing;
using omnislam::testing::jsonNumber;

namespace {

map_t mapOf(const std::vector<Eigen::Vector3d>& pts) {
  map_t m{};
  for (size_t i = 0; i < pts.size(); ++i) {
    landmark_t l{};
    l.id = static_cast<int64_t>(i);
    l.kind = feature_t::KIND_CEILING_LIGHT;
    for (int k = 0; k < 3; ++k) l.position_m[k] = pts[i][k];
    m.landmarks.push_back(l);
  }
  m.num_landmarks = static_cast<int32_t>(pts.size());
  return m;
}

// Truth: a circle of radius 5 m; SLAM: the same rotated by 0.2 rad about the origin and shifted.
// `extra` writes more events at the end of the SLAM log.
void makeLogs(const std::string& slam_path, const std::string& truth_path, bool one_log,
              const std::function<void(lcmio::LogWriter&)>& extra = {}) {
  lcmio::LogWriter slam(slam_path);
  lcmio::LogWriter truth_file(truth_path);
  lcmio::LogWriter& truth = one_log ? slam : truth_file;
  const std::vector<Eigen::Vector3d> lights{{4.5, -5.5, 6.5}, {13.5, -5.5, 6.5}, {4.5, 3.5, 6.5}};
  for (int k = 0; k <= 500; ++k) {
    const int64_t u = 1'000'000 + k * 20'000;
    const double a = 0.01 * k;
    truth.write(u, channels::kGroundTruthPose, t::makePose(u, 5 * std::cos(a), 5 * std::sin(a), a + M_PI / 2));
    if (k % 50 == 0) {
      const double c = std::cos(0.2), s = std::sin(0.2);
      const double x = 5 * std::cos(a), y = 5 * std::sin(a);
      slam.write(u, channels::kSlamPose, t::makePose(u, c * x - s * y + 0.3, s * x + c * y - 0.4, a + M_PI / 2 + 0.2));
      features_t f{};
      f.utime = u;
      slam.write(u, channels::kOmniFeatures, f);
    }
  }
  truth.write(1, channels::kGroundTruthMap, mapOf(lights));
  // Estimated map (in the SLAM frame, unaligned): light 0 exact, light 1 off by 0.5 m, a duplicate
  // of light 0 at 0.3 m, a ghost far away, light 2 missing.
  auto toSlam = [](const Eigen::Vector3d& p) {
    const double c = std::cos(0.2), s = std::sin(0.2);
    return Eigen::Vector3d(c * p.x() - s * p.y() + 0.3, s * p.x() + c * p.y() - 0.4, p.z());
  };
  slam.write(2, channels::kSlamMap,
             mapOf({toSlam(lights[0]), toSlam(lights[1] + Eigen::Vector3d(0.5, 0, 0)),
                    toSlam(lights[0] + Eigen::Vector3d(0, 0.3, 0)), toSlam({40, 40, 6.5})}));
  if (extra) extra(slam);
}

TEST(Eval, AlignedFiguresAreExactAndRawOnesShowTheOffset) {
  t::TempDir dir;
  makeLogs(dir.file("run.lcm"), dir.file("unused.lcm"), true);
  const auto raw = t::run({t::binPath("omnislam-eval"), dir.file("run.lcm"), "--json"}, 30);
  ASSERT_EQ(raw.exit_code, 0) << raw.output;
  EXPECT_GT(jsonNumber(raw.output, "ate_rmse_m"), 0.5) << raw.output;
  EXPECT_EQ(jsonNumber(raw.output, "frames"), 11);
  EXPECT_EQ(jsonNumber(raw.output, "frames_with_pose"), 11);
  const auto al = t::run({t::binPath("omnislam-eval"), dir.file("run.lcm"), "--json", "--align"}, 30);
  ASSERT_EQ(al.exit_code, 0) << al.output;
  EXPECT_NEAR(jsonNumber(al.output, "ate_rmse_m"), 0.0, 1e-6) << al.output;
  EXPECT_NEAR(jsonNumber(al.output, "heading_rmse_rad"), 0.0, 1e-6);
  EXPECT_NEAR(jsonNumber(al.output, "align_theta_rad"), -0.2, 1e-6);
  EXPECT_EQ(jsonNumber(al.output, "landmarks_truth"), 3);
  EXPECT_EQ(jsonNumber(al.output, "landmarks_matched"), 2);
  EXPECT_EQ(jsonNumber(al.output, "landmarks_spurious"), 2) << "the duplicate and the ghost";
  EXPECT_NEAR(jsonNumber(al.output, "landmark_mean_err_m"), 0.25, 1e-6);
  EXPECT_NEAR(jsonNumber(al.output, "landmark_max_err_m"), 0.5, 1e-6);
  // TUM files for evo: one line per pose after the header.
  std::ifstream tum(dir.file("run.lcm") + ".slam.tum");
  ASSERT_TRUE(tum.good());
  int lines = 0;
  for (std::string l; std::getline(tum, l);) lines += l.empty() || l[0] == '#' ? 0 : 1;
  EXPECT_EQ(lines, 11);
  // The table names the figures.
  const auto table =
      t::run({t::binPath("omnislam-eval"), dir.file("run.lcm"), "--align", "--no-tum", "--plot", dir.file("plot")}, 30);
  EXPECT_NE(table.output.find("ATE RMSE"), std::string::npos) << table.output;
  EXPECT_NE(table.output.find("2 spurious"), std::string::npos) << table.output;
  // Headless plots for people: both PNGs decode at their documented sizes.
  const cv::Mat map_png = cv::imread(dir.file("plot") + ".map.png");
  const cv::Mat err_png = cv::imread(dir.file("plot") + ".errors.png");
  EXPECT_EQ(map_png.cols, 1000);
  EXPECT_EQ(map_png.rows, 700);
  EXPECT_EQ(err_png.rows, 520);
  if (const char* keep = std::getenv("OMNISLAM_TEST_ARTIFACTS")) {
    cv::imwrite(std::string(keep) + "/eval.map.png", map_png);
    cv::imwrite(std::string(keep) + "/eval.errors.png", err_png);
  }
}

// A copy of the log at `in` without the SLAM output (SLAM_* channels) logged after `cut_utime`:
// the recording of a SLAM process killed at that time while the rest of the system ran on.
void cutSlamOutput(const std::string& in, const std::string& out, int64_t cut_utime) {
  lcmio::LogWriter w(out);
  lcmio::forEachEvent(in, [&](const lcmio::LogEvent& ev) {
    if (ev.channel.rfind("SLAM_", 0) == 0 && ev.log_utime > cut_utime) return;
    w.write(ev.log_utime, ev.channel, ev.data.data(), static_cast<int32_t>(ev.data.size()));
  });
}

// Every frame answered over the whole run: complete, exit 0, the coverage figures in the JSON.
// The same run with the SLAM output cut after 5 of its 10 s (6 of 11 frames answered): one line
// saying so with the figures, exit 3; --allow-incomplete or lower minimums let it pass.
TEST(Eval, ARunCutInTheMiddleOfTheSlamOutputIsIncomplete) {
  t::TempDir dir;
  makeLogs(dir.file("run.lcm"), dir.file("unused.lcm"), true);
  const auto whole = t::run({t::binPath("omnislam-eval"), dir.file("run.lcm"), "--json", "--no-tum"}, 30);
  ASSERT_EQ(whole.exit_code, 0) << whole.output;
  EXPECT_NE(whole.output.find("\"complete\": true"), std::string::npos) << whole.output;
  EXPECT_EQ(jsonNumber(whole.output, "frames_answered"), 11) << whole.output;
  EXPECT_EQ(jsonNumber(whole.output, "answered_share"), 1.0) << whole.output;
  EXPECT_EQ(jsonNumber(whole.output, "span_share"), 1.0) << whole.output;
  EXPECT_EQ(jsonNumber(whole.output, "reference_span_s"), 10.0) << whole.output;
  EXPECT_EQ(whole.output.find("INCOMPLETE"), std::string::npos) << whole.output;

  cutSlamOutput(dir.file("run.lcm"), dir.file("cut.lcm"), 6'000'000);
  const auto cut = t::run({t::binPath("omnislam-eval"), dir.file("cut.lcm"), "--json", "--no-tum"}, 30);
  EXPECT_EQ(cut.exit_code, 3) << cut.output;
  EXPECT_NE(
      cut.output.find("omnislam-eval: INCOMPLETE RUN: the SLAM answered 6 of 11 frames (54.5 % < --min-answered "
                      "90.0 %); its poses cover 50.0 % of the frames' span of 10.00 s (< --min-span 90.0 %): they "
                      "start 0.00 s after it and end 5.00 s before it"),
      std::string::npos)
      << cut.output;
  EXPECT_NE(cut.output.find("\"complete\": false"), std::string::npos) << cut.output;
  EXPECT_EQ(jsonNumber(cut.output, "frames"), 11) << cut.output;
  EXPECT_EQ(jsonNumber(cut.output, "frames_answered"), 6) << cut.output;
  EXPECT_NEAR(jsonNumber(cut.output, "answered_share"), 6.0 / 11.0, 1e-6) << cut.output;
  EXPECT_NEAR(jsonNumber(cut.output, "span_share"), 0.5, 1e-9) << cut.output;
  EXPECT_NEAR(jsonNumber(cut.output, "pose_end_gap_s"), 5.0, 1e-9) << cut.output;
  EXPECT_NEAR(jsonNumber(cut.output, "truth_end_gap_s"), 5.0, 1e-9) << cut.output;
  EXPECT_EQ(jsonNumber(cut.output, "poses_compared"), 6) << "the figures are still printed" << cut.output;
  // The table says it too.
  const auto table = t::run({t::binPath("omnislam-eval"), dir.file("cut.lcm"), "--no-tum"}, 30);
  EXPECT_EQ(table.exit_code, 3) << table.output;
  EXPECT_NE(table.output.find("coverage: 6 of 11 frames answered (54.5 %)"), std::string::npos) << table.output;
  // Accepted on request: exit 0, still said.
  const auto allowed =
      t::run({t::binPath("omnislam-eval"), dir.file("cut.lcm"), "--json", "--no-tum", "--allow-incomplete"}, 30);
  EXPECT_EQ(allowed.exit_code, 0) << allowed.output;
  EXPECT_NE(allowed.output.find("omnislam-eval: warning: INCOMPLETE RUN"), std::string::npos) << allowed.output;
  // The minimums are the user's: each one alone fails the run, both lowered pass it.
  const auto lower = [&](const std::string& answered, const std::string& span) {
    return t::run({t::binPath("omnislam-eval"), dir.file("cut.lcm"), "--json", "--no-tum", "--min-answered", answered,
                   "--min-span", span},
                  30);
  };
  EXPECT_EQ(lower("0.5", "0.5").exit_code, 0);
  EXPECT_EQ(lower("0.6", "0.5").exit_code, 3);
  EXPECT_EQ(lower("0.5", "0.6").exit_code, 3);
  const auto bad = lower("1.5", "0.5");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--min-answered"), std::string::npos) << bad.output;
}

TEST(Eval, TruthFromASecondLog) {
  t::TempDir dir;
  makeLogs(dir.file("slam.lcm"), dir.file("truth.lcm"), false);
  const auto r = t::run({t::binPath("omnislam-eval"), dir.file("slam.lcm"), "--truth", dir.file("truth.lcm"), "--json",
                         "--align", "--no-tum"},
                        30);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NEAR(jsonNumber(r.output, "ate_rmse_m"), 0.0, 1e-6) << r.output;
  EXPECT_EQ(jsonNumber(r.output, "landmarks_matched"), 2);
}

// A non-finite pose and a truncated one are left out, counted and named, not averaged into the figures.
TEST(Eval, BadMessagesAreSkippedCountedAndNamed) {
  t::TempDir dir;
  makeLogs(dir.file("run.lcm"), dir.file("unused.lcm"), true, [](lcmio::LogWriter& log) {
    const int64_t u = 1'000'000 + 25 * 20'000;  // between two good SLAM poses
    log.write(u, channels::kSlamPose, t::makePose(u, std::nan(""), 0, 0));
    const pose_t whole = t::makePose(u + 1, 0, 0, 0);
    std::vector<uint8_t> bytes(static_cast<size_t>(whole.getEncodedSize()));
    whole.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    log.write(u + 1, channels::kSlamPose, bytes.data(), static_cast<int32_t>(bytes.size() - 3));
  });
  const auto r = t::run({t::binPath("omnislam-eval"), dir.file("run.lcm"), "--json", "--align", "--no-tum"}, 30);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NEAR(jsonNumber(r.output, "ate_rmse_m"), 0.0, 1e-6) << r.output;
  EXPECT_EQ(jsonNumber(r.output, "frames_with_pose"), 11) << r.output;
  EXPECT_EQ(jsonNumber(r.output, "messages_skipped"), 2) << r.output;
  EXPECT_NE(r.output.find("skipped 1 message of " + dir.file("run.lcm") + ": SLAM_POSE: non-finite pose"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("SLAM_POSE: undecodable (corrupt)"), std::string::npos) << r.output;
}

TEST(Eval, ALogWithoutSlamOutputIsAClearError) {
  t::TempDir dir;
  {
    lcmio::LogWriter log(dir.file("empty.lcm"));
    log.write(1, channels::kGroundTruthPose, t::makePose(1, 0, 0, 0));
  }
  const auto r = t::run({t::binPath("omnislam-eval"), dir.file("empty.lcm"), "--no-tum"}, 30);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("no SLAM_POSE message"), std::string::npos) << r.output;
}

// Nothing compared is an error, not ATE 0: truth only after the estimate, or truth too sparse to
// bridge (samples more than 0.2 s apart) everywhere.
TEST(Eval, NoComparedPoseIsAnErrorNotAZeroAte) {
  t::TempDir dir;
  {
    lcmio::LogWriter log(dir.file("after.lcm"));
    for (int k = 0; k < 10; ++k) log.write(k, channels::kSlamPose, t::makePose(1'000'000 + k * 100'000, k, 0, 0));
    for (int k = 0; k < 10; ++k)
      log.write(k, channels::kGroundTruthPose, t::makePose(5'000'000 + k * 100'000, k, 0, 0));
  }
  {
    lcmio::LogWriter log(dir.file("sparse.lcm"));
    for (int k = 0; k < 10; ++k) log.write(k, channels::kSlamPose, t::makePose(1'050'000 + k * 500'000, k, 0, 0));
    for (int k = 0; k < 10; ++k)
      log.write(k, channels::kGroundTruthPose, t::makePose(1'000'000 + k * 500'000, k, 0, 0));
  }
  for (const char* name : {"after.lcm", "sparse.lcm"})
    for (const bool align : {false, true}) {
      std::vector<std::string> argv{t::binPath("omnislam-eval"), dir.file(name), "--json", "--no-tum"};
      if (align) argv.push_back("--align");
      const auto r = t::run(argv, 30);
      EXPECT_EQ(r.exit_code, 2) << name << "\n" << r.output;
      EXPECT_NE(r.output.find("no SLAM_POSE could be compared"), std::string::npos) << name << "\n" << r.output;
      EXPECT_EQ(r.output.find("ate_rmse_m"), std::string::npos) << name << "\n" << r.output;
    }
}

// One SLAM pose at x = 1e300: the RMSE is finite and at most the max (its squares would overflow);
// --align cannot fit such a trajectory and says so instead of printing "-nan".
TEST(Eval, AHugePoseGivesAnHonestRmseAndAlignRefusesIt) {
  t::TempDir dir;
  makeLogs(dir.file("run.lcm"), dir.file("unused.lcm"), true, [](lcmio::LogWriter& log) {
    const int64_t u = 1'000'000 + 25 * 20'000;
    log.write(u, channels::kSlamPose, t::makePose(u, 1e300, 0, 0));
  });
  const auto raw = t::run({t::binPath("omnislam-eval"), dir.file("run.lcm"), "--json", "--no-tum"}, 30);
  ASSERT_EQ(raw.exit_code, 0) << raw.output;
  const double rmse = jsonNumber(raw.output, "ate_rmse_m"), max = jsonNumber(raw.output, "ate_max_m");
  EXPECT_TRUE(std::isfinite(rmse)) << raw.output;
  EXPECT_LE(rmse, max) << raw.output;
  EXPECT_NEAR(rmse / (1e300 / std::sqrt(12.0)), 1.0, 1e-5) << raw.output;  // printed with 6 digits
  const auto al = t::run({t::binPath("omnislam-eval"), dir.file("run.lcm"), "--json", "--no-tum", "--align"}, 30);
  EXPECT_EQ(al.exit_code, 2) << al.output;
  EXPECT_NE(al.output.find("--align: "), std::string::npos) << al.output;
  EXPECT_EQ(al.output.find("nan"), std::string::npos) << al.output;
  EXPECT_EQ(al.output.find("inf"), std::string::npos) << al.output;
}

// An estimate standing still (1 um jitter) against a moving truth has no heading to align: the
// degeneracy test is relative to the trajectories' spread, not an absolute 1e-12.
TEST(Eval, AlignRefusesAnEstimateThatDoesNotMove) {
  t::TempDir dir;
  {
    lcmio::LogWriter log(dir.file("still.lcm"));
    for (int k = 0; k <= 100; ++k) {
      const int64_t u = 1'000'000 + k * 100'000;
      log.write(u, channels::kGroundTruthPose, t::makePose(u, 5 * std::cos(0.03 * k), 5 * std::sin(0.03 * k), 0));
      log.write(u, channels::kSlamPose, t::makePose(u, 2 + 1e-6 * std::sin(7.0 * k), 1e-6 * std::cos(5.0 * k), 0));
    }
  }
  const auto r = t::run({t::binPath("omnislam-eval"), dir.file("still.lcm"), "--json", "--no-tum", "--align"}, 30);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--align: trajectory degenerate"), std::string::npos) << r.output;
  // Without --align it is scored as it is.
  const auto raw = t::run({t::binPath("omnislam-eval"), dir.file("still.lcm"), "--json", "--no-tum"}, 30);
  EXPECT_EQ(raw.exit_code, 0) << raw.output;
}

// A straight run of 11 poses (SLAM = truth) with `extra` written after them: for the tests of
// repeated utimes, the map kept and the table's wording.
void writeLine(const std::string& path, const std::function<void(lcmio::LogWriter&)>& extra) {
  lcmio::LogWriter log(path);
  for (int k = 0; k <= 10; ++k) {
    const int64_t u = 1'000'000 + k * 100'000;
    log.write(u, channels::kGroundTruthPose, t::makePose(u, k, 0, 0));
    log.write(u, channels::kSlamPose, t::makePose(u, k, 0, 0));
  }
  extra(log);
}

// A second SLAM_POSE at a utime already read replaces the first and is counted; the SLAM_MAP kept is
// the one with the newest utime, not the last in file order (the older one is counted).
TEST(Eval, RepeatedUtimesAreCountedAndTheNewestMapIsKept) {
  t::TempDir dir;
  writeLine(dir.file("dup.lcm"), [](lcmio::LogWriter& log) {
    log.write(2'000'000, channels::kSlamPose, t::makePose(1'500'000, 5, 0, 0));  // the same pose again
    map_t truth = mapOf({{2, 1, 0}, {6, 1, 0}});
    log.write(2'000'000, channels::kGroundTruthMap, truth);
    map_t newest = mapOf({{2, 1.1, 0}, {6, 1.1, 0}});
    newest.utime = 2'000'000;
    log.write(2'000'000, channels::kSlamMap, newest);
    map_t older = mapOf({{40, 40, 0}});
    older.utime = 1'900'000;
    log.write(2'000'001, channels::kSlamMap, older);
  });
  const auto r = t::run({t::binPath("omnislam-eval"), dir.file("dup.lcm"), "--json", "--no-tum"}, 30);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(jsonNumber(r.output, "messages_skipped"), 2) << r.output;
  EXPECT_EQ(jsonNumber(r.output, "landmarks_matched"), 2) << r.output;
  EXPECT_EQ(jsonNumber(r.output, "frames_with_pose"), 11) << r.output;
  EXPECT_NE(r.output.find("skipped 1 message of " + dir.file("dup.lcm") + ": SLAM_POSE: utime already read"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("SLAM_MAP: older than one already read"), std::string::npos) << r.output;
}

// The table says what was not compared: precision of no association is "n/a (0/0)", frames left out
// for differing feature counts are counted, and a log without GROUND_TRUTH_MAP has "no truth map".
TEST(Eval, TheTableSaysWhatWasNotCompared) {
  t::TempDir dir;
  auto assocAndLabels = [](lcmio::LogWriter& log) {
    for (int k = 0; k <= 10; ++k) {
      const int64_t u = 1'000'000 + k * 100'000;
      associations_t a{};
      a.utime = u;
      a.landmark_id = {associations_t::NOT_ASSOCIATED};
      feature_labels_t l{};
      l.utime = u;
      l.landmark_id = {0};
      l.source_code = {0};
      if (k == 10) l.landmark_id.push_back(1), l.source_code.push_back(0);  // counts differ: left out
      a.num_features = static_cast<int32_t>(a.landmark_id.size());
      l.num_features = static_cast<int32_t>(l.landmark_id.size());
      log.write(u, channels::kSlamAssociations, a);
      log.write(u, channels::kGroundTruthFeatureLabels, l);
    }
    log.write(2'000'000, channels::kSlamMap, mapOf({{2, 1, 0}}));
  };
  writeLine(dir.file("assoc.lcm"), [&](lcmio::LogWriter& log) {
    assocAndLabels(log);
    log.write(2'000'000, channels::kGroundTruthMap, mapOf({{2, 1, 0}}));
  });
  const auto r = t::run({t::binPath("omnislam-eval"), dir.file("assoc.lcm"), "--no-tum"}, 30);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("precision n/a (0/0)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("10 frames, 1 left out"), std::string::npos) << r.output;
  writeLine(dir.file("notruthmap.lcm"), assocAndLabels);
  const auto n = t::run({t::binPath("omnislam-eval"), dir.file("notruthmap.lcm"), "--no-tum"}, 30);
  ASSERT_EQ(n.exit_code, 0) << n.output;
  EXPECT_NE(n.output.find("no truth map"), std::string::npos) << n.output;
  EXPECT_EQ(n.output.find("0 true"), std::string::npos) << n.output;
  EXPECT_EQ(n.output.find("landmark error mean 0 m"), std::string::npos) << n.output;
}

// Landmark matching is solved per group of landmarks within the gate of each other: 4000 against
// 4000 on a 10 m grid (a dense 4000 x 4000 Hungarian took 112 s) is matched at once; 6000 against
// 6000 all within the gate of each other (a 36e6-cell assignment) is refused with the reason.
TEST(Eval, LandmarkMatchingSolvesGroupsAndRefusesOneTooLarge) {
  t::TempDir dir;
  writeLine(dir.file("grid.lcm"), [](lcmio::LogWriter& log) {
    std::vector<Eigen::Vector3d> est, truth;
    for (int k = 0; k < 4000; ++k) {
      truth.emplace_back(10.0 * (k % 64), 10.0 * (k / 64), 0);
      est.emplace_back(10.0 * (k % 64) + 0.1, 10.0 * (k / 64), 0);
    }
    log.write(2'000'000, channels::kGroundTruthMap, mapOf(truth));
    log.write(2'000'000, channels::kSlamMap, mapOf(est));
  });
  const auto r = t::run({t::binPath("omnislam-eval"), dir.file("grid.lcm"), "--json", "--no-tum"}, 30);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(jsonNumber(r.output, "landmarks_matched"), 4000) << r.output;
  EXPECT_NEAR(jsonNumber(r.output, "landmark_max_err_m"), 0.1, 1e-9) << r.output;
  writeLine(dir.file("crowd.lcm"), [](lcmio::LogWriter& log) {
    std::vector<Eigen::Vector3d> est, truth;
    for (int k = 0; k < 6000; ++k) {
      truth.emplace_back(1e-4 * k, 0, 0);
      est.emplace_back(1e-4 * k, 0.1, 0);
    }
    log.write(2'000'000, channels::kGroundTruthMap, mapOf(truth));
    log.write(2'000'000, channels::kSlamMap, mapOf(est));
  });
  const auto crowd = t::run({t::binPath("omnislam-eval"), dir.file("crowd.lcm"), "--json", "--no-tum"}, 30);
  EXPECT_EQ(crowd.exit_code, 2) << crowd.output;
  EXPECT_NE(crowd.output.find("landmark matching: 6000 estimated and 6000 true landmarks lie within the gate of each "
                              "other: an assignment over 25000000 cells would not fit; a smaller gate splits them "
                              "(--gate 2 m)"),
            std::string::npos)
      << crowd.output;
}

// Without OMNI_FEATURES the truth's span is the reference: poses over its first half are incomplete;
// a run whose truth ends with the poses (e.g. a shorter --duration) is complete.
TEST(Eval, WithoutFramesThePosesAreCheckedAgainstTheTruthsSpan) {
  t::TempDir dir;
  writeLine(dir.file("half.lcm"), [](lcmio::LogWriter& log) {
    for (int k = 11; k <= 20; ++k)
      log.write(0, channels::kGroundTruthPose, t::makePose(1'000'000 + k * 100'000, k, 0, 0));
  });
  const auto r = t::run({t::binPath("omnislam-eval"), dir.file("half.lcm"), "--json", "--no-tum"}, 30);
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("its poses cover 50.0 % of the truth's span of 2.00 s (< --min-span 90.0 %)"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("\"coverage_reference\": \"truth\""), std::string::npos) << r.output;
  writeLine(dir.file("line.lcm"), [](lcmio::LogWriter&) {});
  const auto whole = t::run({t::binPath("omnislam-eval"), dir.file("line.lcm"), "--json", "--no-tum"}, 30);
  EXPECT_EQ(whole.exit_code, 0) << whole.output;
  EXPECT_EQ(jsonNumber(whole.output, "span_share"), 1.0) << whole.output;
}

}  // namespace
