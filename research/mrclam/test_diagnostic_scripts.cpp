// The four MRCLAM diagnostic scripts whose figures docs/results/mrclam.md and research/mrclam-diagnosis.md quote
// (research/mrclam/mrclam_odometry_heading.py, mrclam_bearing_correlation.py, mrclam_visual_rotation.py,
// mrclam_group_observability.py), each on a small MRCLAM-format dataset the test writes with a known
// answer: a turn-scale error the fit must recover, residuals whose correlation is -1 and +1 by
// construction, a spin in place whose rotation the landmarks' bearings give exactly, and a group
// seen with a fixed pattern of misses and passing robots. Plus what each does with input it cannot
// use.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include "mrclam_files.h"
#include "proc_util.h"

namespace {

namespace t = omnislam::testing;

/// One robot, 10 Hz odometry and truth for `seconds`, driving at v with the commanded turn rate
/// omega(k) while the truth turns at turn_scale * omega (the truth is integrated exactly, with the
/// odometry's own rectangle rule). Writes Robot1_Odometry.dat and Robot1_Groundtruth.dat.
template <typename Omega>
void writeRobot(const t::TempDir& d, double seconds, double v, Omega omega, double turn_scale,
                std::string* measurements = nullptr, double frame_every_s = 0.0,
                const std::vector<std::pair<double, double>>& landmarks = {}) {
  std::string odo, truth;
  char line[160];
  double x = 0.0, y = 0.0, th = 0.0;
  const double dt = 0.1;
  const int steps = static_cast<int>(std::lround(seconds / dt));
  const int frame_every = frame_every_s > 0.0 ? static_cast<int>(std::lround(frame_every_s / dt)) : 0;
  for (int k = 0; k <= steps; ++k) {
    const double time = 1000.0 + dt * k, w = omega(k);
    std::snprintf(line, sizeof line, "%.3f %.3f %.6f\n", time, v, w);
    odo += line;
    std::snprintf(line, sizeof line, "%.3f %.6f %.6f %.9f\n", time, x, y, th);
    truth += line;
    if (measurements && frame_every && k > 0 && k % frame_every == 0) {
      for (size_t j = 0; j < landmarks.size(); ++j) {
        const double b = std::remainder(std::atan2(landmarks[j].second - y, landmarks[j].first - x) - th, 2.0 * M_PI);
        if (std::abs(b) > 0.6) continue;
        std::snprintf(line, sizeof line, "%.3f %d 3.0 %.9f\n", time, 60 + static_cast<int>(j), b);
        *measurements += line;
      }
    }
    x += v * dt * std::cos(th);
    y += v * dt * std::sin(th);
    th += turn_scale * w * dt;
  }
  t::writeMrclamFile(d.file("Robot1_Odometry.dat"), odo);
  t::writeMrclamFile(d.file("Robot1_Groundtruth.dat"), truth);
}

/// Barcodes 60, 61, ... for landmark subjects 6, 7, ... and barcode 14 for robot 2; the landmarks
/// at `xy`.
void writeLandmarks(const t::TempDir& d, const std::vector<std::pair<double, double>>& xy) {
  std::string barcodes = "1 5\n2 14\n", lms;
  for (size_t j = 0; j < xy.size(); ++j) {
    barcodes += std::to_string(6 + j) + " " + std::to_string(60 + j) + "\n";
    lms += std::to_string(6 + j) + " " + std::to_string(xy[j].first) + " " + std::to_string(xy[j].second) +
           " 0.001 0.001\n";
  }
  t::writeMrclamFile(d.file("Barcodes.dat"), barcodes);
  t::writeMrclamFile(d.file("Landmark_Groundtruth.dat"), lms);
}

t::RunResult script(const std::string& name, const std::vector<std::string>& args) {
  std::vector<std::string> argv = {"python3", t::sourcePath("research/mrclam/" + name)};
  argv.insert(argv.end(), args.begin(), args.end());
  return t::run(argv, 60.0);
}

bool has(const std::string& output, const std::string& text) { return output.find(text) != std::string::npos; }

/// Whether `pattern` (ECMAScript) matches somewhere in `output`.
bool matches(const std::string& output, const std::string& pattern) {
  return std::regex_search(output, std::regex(pattern));
}

/// The script `name` stops (exit != 0, no traceback) on a bad option value and on a folder without
/// the dataset, and says which.
void expectRefusals(const std::string& name, const t::TempDir& d, const std::vector<std::string>& bad_option) {
  std::vector<std::string> args = {d.path()};
  args.insert(args.end(), bad_option.begin(), bad_option.end());
  const auto bad = script(name, args);
  EXPECT_NE(bad.exit_code, 0) << name;
  EXPECT_TRUE(has(bad.output, bad_option[0])) << name << ": " << bad.output;
  const auto missing = script(name, {d.file("nothing-here")});
  EXPECT_NE(missing.exit_code, 0) << name;
  EXPECT_TRUE(has(missing.output, "is the MRCLAM dataset present?")) << name << ": " << missing.output;
  EXPECT_FALSE(has(bad.output + missing.output, "Traceback")) << name;
}

TEST(MrclamDiagnosticScripts, OdometryHeadingRecoversAKnownTurnScale) {
  t::TempDir d;
  // 10 s turning left at 0.3 rad/s, 10 s straight, 10 s turning right at 0.2 rad/s, repeated; the
  // robot turns 5 % less than commanded, with no drift per metre.
  const auto omega = [](int k) {
    const int phase = (k / 100) % 3;
    return phase == 0 ? 0.3 : phase == 1 ? 0.0 : -0.2;
  };
  writeRobot(d, 120.0, 0.1, omega, 0.95);
  const auto r = script("mrclam_odometry_heading.py", {d.path(), "--window-s", "5", "--block-s", "60"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // 24 windows (the last odometry line ends the run), 8 of them straight and 16 turning; the drift
  // may print as +0.000 or -0.000 (rounding noise of the files' decimals).
  EXPECT_TRUE(matches(r.output, R"(robot 1: 24 windows of 5 s; drift [+-]0\.000 rad/m, turn scale -0\.050;)"))
      << r.output;
  EXPECT_TRUE(has(r.output, "0.000 after the fit")) << r.output;
  EXPECT_TRUE(matches(r.output, R"(per 60 s block \(drift/turn scale\): [+-]0\.000/-0\.050 [+-]0\.000/-0\.050\n)"))
      << r.output;
  // Straight windows have no error; turning ones 5 % of their turn: 0.075 and 0.050 rad, RMS 0.064.
  EXPECT_TRUE(has(r.output, "straight 8: RMS 0.000 rad")) << r.output;
  EXPECT_TRUE(has(r.output, "turning 16: RMS 0.064 rad")) << r.output;

  expectRefusals("mrclam_odometry_heading.py", d, {"--window-s", "0"});
}

TEST(MrclamDiagnosticScripts, OdometryHeadingNamesTheBadLine) {
  t::TempDir d;
  writeRobot(
      d, 20.0, 0.1, [](int) { return 0.1; }, 1.0);
  t::writeMrclamFile(d.file("Robot1_Odometry.dat"), "1000.0 0.1 0.1\n1000.1 0.1 x\n");
  const auto r = script("mrclam_odometry_heading.py", {d.path()});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(has(r.output, "Robot1_Odometry.dat:6: a field is not a number")) << r.output;
  EXPECT_FALSE(has(r.output, "Traceback")) << r.output;
}

TEST(MrclamDiagnosticScripts, BearingCorrelationOfAlternatingResidualsIsMinusOneThenPlusOne) {
  t::TempDir d;
  writeLandmarks(d, {{3.0, 1.0}});
  // The robot stands at the origin facing +x; 40 sightings 0.5 s apart, each residual 0.01 (a yaw
  // offset, removed as the robot's mean) + 0.005 (-1)^k: lag 0.5 s correlates -1, lag 1 s +1.
  writeRobot(
      d, 30.0, 0.0, [](int) { return 0.0; }, 1.0);
  std::string meas;
  char line[120];
  const double truth = std::atan2(1.0, 3.0);
  for (int k = 0; k < 40; ++k) {
    std::snprintf(line, sizeof line, "%.3f 60 3.2 %.9f\n", 1000.5 + 0.5 * k, truth + 0.01 + (k % 2 ? -0.005 : 0.005));
    meas += line;
  }
  t::writeMrclamFile(d.file("Robot1_Measurement.dat"), meas);
  const auto r = script("mrclam_bearing_correlation.py", {d.path()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(has(r.output, "40 landmark sightings of 1 robots; residual RMS 0.0050 rad")) << r.output;
  // Pairs per lag bin: 39 at 0.5 s, 38 at 1.0 s, 37 at 1.5 s.
  EXPECT_TRUE(matches(r.output, R"( 0\.35- 0\.70 +39 -1\.00 \|)")) << r.output;
  EXPECT_TRUE(matches(r.output, R"( 1\.00- 1\.50 +38 +1\.00 \|)")) << r.output;
  EXPECT_TRUE(matches(r.output, R"( 1\.50- 2\.00 +37 -1\.00 \|)")) << r.output;

  // Residuals that are all equal leave nothing once the mean is removed: a message, not a crash.
  meas.clear();
  for (int k = 0; k < 10; ++k) {
    std::snprintf(line, sizeof line, "%.3f 60 3.2 %.9f\n", 1000.5 + 0.5 * k, truth + 0.01);
    meas += line;
  }
  t::writeMrclamFile(d.file("Robot1_Measurement.dat"), meas);
  const auto flat = script("mrclam_bearing_correlation.py", {d.path()});
  EXPECT_NE(flat.exit_code, 0);
  EXPECT_TRUE(has(flat.output, "every residual is zero")) << flat.output;
  EXPECT_FALSE(has(flat.output, "Traceback")) << flat.output;

  // Each landmark seen once: no same-landmark pair to fit. The fit's grid used to "fit" the empty
  // sum and print rho0 0.05, tau 0.5 s.
  writeLandmarks(d, {{3.0, 1.0}, {3.0, -1.0}});
  meas.clear();
  std::snprintf(line, sizeof line, "1000.5 60 3.2 %.9f\n", truth + 0.01);
  meas += line;
  std::snprintf(line, sizeof line, "1001.0 61 3.2 %.9f\n", -truth - 0.02);
  meas += line;
  t::writeMrclamFile(d.file("Robot1_Measurement.dat"), meas);
  const auto once = script("mrclam_bearing_correlation.py", {d.path()});
  EXPECT_NE(once.exit_code, 0) << once.output;
  EXPECT_TRUE(has(once.output, "no same-landmark pair below --fit-max-lag-s")) << once.output;
  EXPECT_FALSE(has(once.output, "fit over lags")) << once.output;

  expectRefusals("mrclam_bearing_correlation.py", d, {"--fit-max-lag-s", "0"});
}

TEST(MrclamDiagnosticScripts, VisualRotationOfASpinInPlaceIsExact) {
  t::TempDir d;
  // A ring of 8 landmarks 3 m around the origin; the robot spins in place at a commanded 0.3 rad/s
  // but turns 5 % slower; a frame every 0.2 s with the exact bearing of every landmark within
  // +-0.6 rad, so every pair of consecutive frames shares a landmark.
  std::vector<std::pair<double, double>> ring;
  for (int j = 0; j < 8; ++j) {
    const double a = 0.25 * M_PI * j + 0.1;
    ring.emplace_back(3.0 * std::cos(a), 3.0 * std::sin(a));
  }
  writeLandmarks(d, ring);
  std::string meas;
  writeRobot(
      d, 60.0, 0.0, [](int) { return 0.3; }, 0.95, &meas, 0.2, ring);
  meas = "1000.100 14 2.0 0.1\n" + meas;  // robot 2 in the view: not a landmark, left out
  t::writeMrclamFile(d.file("Robot1_Measurement.dat"), meas);
  // A bearing sigma far below the commanded rotation's makes the fused heading the visual one.
  const auto r = script("mrclam_visual_rotation.py", {d.path(), "--bearing-sigma-rad", "1e-6"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Each 0.2 s pair: commanded 0.06 rad, true 0.057 rad, so the commanded error is 0.003 rad.
  EXPECT_TRUE(has(r.output,
                  "robot 1: 299 turning frame pairs, rotation error RMS visual 0.0000 rad, commanded 0.0030 rad; "
                  "100 % of the turning inside a measured pair"))
      << r.output;
  // Over 5 s the commanded heading is 5 % of 1.5 rad off, the fused one exact (its first 0.2 s
  // before the first frame aside, which only the first window holds).
  // 0.003 rad in the first of 12 windows: RMS 0.0009.
  EXPECT_TRUE(has(r.output, "5 s windows: heading error RMS commanded 0.075, fused 0.001 rad")) << r.output;

  expectRefusals("mrclam_visual_rotation.py", d, {"--max-gap-s", "0"});
}

TEST(MrclamDiagnosticScripts, GroupObservabilityOfExactBearingsFromADrive) {
  t::TempDir d;
  // One landmark ahead and to the left; the robot drives an arc towards it at 0.05 m/s, commanded 0.01 rad/s,
  // truly 0.009 rad/s; a frame every 0.5 s with the exact bearing whenever it is within +-0.6 rad.
  const std::vector<std::pair<double, double>> lm = {{4.0, 1.0}};
  writeLandmarks(d, lm);
  std::string meas;
  writeRobot(
      d, 120.0, 0.05, [](int) { return 0.01; }, 0.9, &meas, 0.5, lm);
  t::writeMrclamFile(d.file("Robot1_Measurement.dat"), meas);
  const auto r = script("mrclam_group_observability.py", {d.path()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(has(r.output, "1 landmarks in 1 groups (link 0.5 m): 1: 6 at (4.00, 1.00)")) << r.output;
  // The heading error grows by 0.001 rad/s: 0.57, 1.72 and 3.44 deg over 10, 30 and 60 s, in every
  // window, so the median is the 90th percentile.
  EXPECT_TRUE(has(r.output,
                  "dead reckoning heading error: 10 s median 0.6 / p90 0.6 deg, 30 s median 1.7 / "
                  "p90 1.7 deg, 60 s median 3.4 / p90 3.4 deg"))
      << r.output;
  // Exact bearings from the true poses cross at the landmark, the group's centre, in every window
  // with enough parallax (there are some).
  EXPECT_TRUE(matches(r.output, R"(triangulated from the true poses: 20 s windows [1-9][0-9]*, median error 0\.00 m; )"
                                R"(40 s windows [1-9][0-9]*, median error 0\.00 m)"))
      << r.output;
  // Every frame with the group in view has its sighting; every sighting is in its own group's gate.
  EXPECT_TRUE(matches(r.output, R"(detection in view: P_D 1\.00 over [1-9][0-9]* group-frames; miss runs 0, p90 nan, )"
                                R"(p99 nan, longest 0 frames)"))
      << r.output;
  EXPECT_TRUE(has(r.output, "landmark sightings to their own group 100.0 %, to none 0.0 %")) << r.output;
  EXPECT_TRUE(has(r.output, "visits (gap 10 s): 1, per group 1;")) << r.output;

  expectRefusals("mrclam_group_observability.py", d, {"--gate-sigma", "0"});
}

TEST(MrclamDiagnosticScripts, GroupObservabilityCountsMissesVisitsAndPassingRobots) {
  t::TempDir d;
  // Landmarks 6 and 7 0.2 m apart form one group centred 3 m ahead; landmark 8 stands alone behind.
  writeLandmarks(d, {{3.0, 0.1}, {3.0, -0.1}, {-4.0, 0.0}});
  writeRobot(
      d, 30.0, 0.0, [](int) { return 0.0; }, 1.0);  // standing at the origin facing +x
  // 60 frames 0.5 s apart. Landmark 6 is reported in frames k with k % 3 != 2, except k = 20..44:
  // 24 detections of 60 frames in view, misses in runs of 1 (k = 2, 5, ..., 17 and 47, ..., 56;
  // k = 59 is not closed by a detection) and one of 25 (20..44), which splits the sightings into two
  // visits (1010.0 s, then 1023.0 s). Robot 2 (barcode 14) is in every frame, on the group's bearing
  // in the first 15 and 0.5 rad off after; one unknown barcode.
  std::string meas = "1000.500 99 2.0 0.3\n";
  char line[120];
  for (int k = 0; k < 60; ++k) {
    const double time = 1000.5 + 0.5 * k;
    if (k % 3 != 2 && (k < 20 || k > 44)) {
      std::snprintf(line, sizeof line, "%.3f 60 3.0 %.9f\n", time, std::atan2(0.1, 3.0));
      meas += line;
    }
    std::snprintf(line, sizeof line, "%.3f 14 2.0 %.9f\n", time, k < 15 ? 0.0 : 0.5);
    meas += line;
  }
  t::writeMrclamFile(d.file("Robot1_Measurement.dat"), meas);
  const auto r = script("mrclam_group_observability.py", {d.path()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(has(r.output, "3 landmarks in 2 groups (link 0.5 m): 1: 6,7 at (3.00, 0.00); 2: 8 at (-4.00, 0.00)"))
      << r.output;
  EXPECT_TRUE(has(r.output, "robot 1: 85 sightings: landmarks 24 (28 %), other robots 60 (71 %), unknown barcodes 1"))
      << r.output;
  EXPECT_TRUE(has(r.output, "visits (gap 10 s): 2, per group 2 0; parallax per visit median 0.0 deg")) << r.output;
  // Runs [1 x 10, 25]: the 90th percentile is 1, the 99th 1 + 0.9 * 24 = 22.6.
  EXPECT_TRUE(
      has(r.output, "detection in view: P_D 0.40 over 60 group-frames; miss runs 11, p90 1, p99 23, longest 25 frames"))
      << r.output;
  // Landmark 6 is 0.033 rad off the group's centre: 0.9 of the widened sigma, sqrt(1 deg^2 +
  // (0.1 m / 3 m)^2). Robot 2 is in the gate in 15 of its 60 sightings.
  EXPECT_TRUE(has(r.output,
                  "landmark sightings to their own group 100.0 %, to none 0.0 %; other robots' sightings "
                  "inside a gate 25.0 %"))
      << r.output;
  // Standing still: no heading error, and no window with parallax to triangulate from.
  EXPECT_TRUE(has(r.output, "10 s median 0.0 / p90 0.0 deg")) << r.output;
  EXPECT_TRUE(has(r.output, "20 s windows 0, median error nan m")) << r.output;

  // The same without the truth file: the script names it.
  std::remove(d.file("Robot1_Groundtruth.dat").c_str());
  const auto missing = script("mrclam_group_observability.py", {d.path()});
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_TRUE(has(missing.output, "Robot1_Groundtruth.dat")) << missing.output;
  EXPECT_FALSE(has(missing.output, "Traceback")) << missing.output;
}

}  // namespace
