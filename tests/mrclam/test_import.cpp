// omnislam-import-mrclam's library on small MRCLAM-format files written by the test: a good
// dataset (counts, frames, labels, odometry integration, event order, start pose), every malformed
// case with file and line in the message, the duplicated-time policy, dropping robot sightings, no
// appearance in the features, and the true map (localisation in it).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>

#include "omnislam/runtime/map_file.h"
#include "mrclam_import.h"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "mrclam_files.h"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

/// A tiny dataset for robot 1: odometry 1 m/s straight for 1 s, then turning; truth; 3 frames.
void writeDataset(const t::TempDir& d, const std::string& odometry = "") {
  t::writeMrclamFile(d.file("Barcodes.dat"), "1 5\n2 14\n6 63\n7 81\n");
  t::writeMrclamFile(d.file("Landmark_Groundtruth.dat"), "6 1.0 2.0 0.001 0.002\n7 -1.0 0.5 0.001 0.001\n");
  t::writeMrclamFile(d.file("Robot1_Odometry.dat"),
                     odometry.empty() ? "100.0 1.0 0.0\n100.5 1.0 0.0\n101.0 0.5 0.5\n102.0 0.0 0.0\n" : odometry);
  std::string truth;
  for (int k = 0; k <= 30; ++k) {
    char line[128];
    std::snprintf(line, sizeof line, "%.3f %.4f 3.0 0.1\n", 99.9 + 0.1 * k, 2.0 + 0.1 * k);
    truth += line;
  }
  t::writeMrclamFile(d.file("Robot1_Groundtruth.dat"), truth);
  // Frame 1 at 100.2: landmark 63 and robot 2 (barcode 14); frame 2 at 100.7: unknown code 43;
  // frame 3 at 101.5: landmark 81 and the robot's own barcode 5.
  t::writeMrclamFile(d.file("Robot1_Measurement.dat"),
                     "100.2 63 3.0 0.25\n100.2 14 2.0 -0.30\n100.7 43 4.0 0.1\n101.5 81 2.5 -0.5\n101.5 5 1.0 0.05\n");
}

struct Decoded {
  std::vector<odometry_t> odometry;
  std::vector<features_t> features;
  std::vector<feature_labels_t> labels;
  std::vector<pose_t> truth;
  std::vector<map_t> maps;
};

Decoded decode(const mrclam::ImportedLog& log) {
  Decoded d;
  for (const auto& e : log.events) {
    const int n = static_cast<int>(e.data.size());
    if (e.channel == channels::kOdometry) d.odometry.emplace_back().decode(e.data.data(), 0, n);
    if (e.channel == channels::kOmniFeatures) d.features.emplace_back().decode(e.data.data(), 0, n);
    if (e.channel == channels::kGroundTruthFeatureLabels) d.labels.emplace_back().decode(e.data.data(), 0, n);
    if (e.channel == channels::kGroundTruthPose) d.truth.emplace_back().decode(e.data.data(), 0, n);
    if (e.channel == channels::kGroundTruthMap) d.maps.emplace_back().decode(e.data.data(), 0, n);
  }
  return d;
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const mrclam::ParseError& e) {
    return e.what();
  }
  return "";
}

TEST(MrclamImport, GoodDatasetCountsFramesLabelsAndOrder) {
  t::TempDir d;
  writeDataset(d);
  mrclam::ImportOptions o;
  o.bearing_sigma_rad = 0.02;
  const auto log = mrclam::importRobot(d.path(), o);
  const auto& r = log.report;
  EXPECT_EQ(r.odometry_file.data_lines, 4);
  EXPECT_EQ(r.odometry_file.comment_lines, 4);
  EXPECT_EQ(r.measurements, 5);
  EXPECT_EQ(r.frames, 3);
  EXPECT_EQ(r.features, 5);
  EXPECT_EQ(r.landmark_sightings, 2);
  EXPECT_EQ(r.robot_sightings, 1);
  EXPECT_EQ(r.robot_sightings_dropped, 0);
  EXPECT_EQ(r.unknown_code_sightings, 1);
  EXPECT_EQ(r.own_code_sightings, 1);
  ASSERT_EQ(r.unknown_codes.size(), 1u);
  EXPECT_EQ(r.unknown_codes[0], 43);
  EXPECT_EQ(r.landmark_sightings + r.robot_sightings + r.unknown_code_sightings + r.own_code_sightings, r.measurements);

  const Decoded dec = decode(log);
  ASSERT_EQ(dec.features.size(), 3u);
  ASSERT_EQ(dec.labels.size(), 3u);
  EXPECT_EQ(dec.features[0].utime, 100'200'000);
  ASSERT_EQ(dec.features[0].num_features, 2);
  const feature_t& f0 = dec.features[0].features[0];
  EXPECT_EQ(f0.kind, +feature_t::KIND_VERTICAL_LINE);
  EXPECT_FALSE(f0.has_elevation);
  EXPECT_DOUBLE_EQ(f0.azimuth_rad, 0.25);
  EXPECT_NEAR(f0.covariance[0][0], 0.0004, 1e-12);
  EXPECT_EQ(dec.labels[0].features_seq, dec.features[0].seq);
  EXPECT_EQ(dec.labels[0].landmark_id[0], 6);
  EXPECT_EQ(dec.labels[0].landmark_id[1], +feature_labels_t::OTHER_ROBOT);
  EXPECT_EQ(dec.labels[0].source_code[1], 14);
  EXPECT_EQ(dec.labels[1].landmark_id[0], +feature_labels_t::UNKNOWN);
  EXPECT_EQ(dec.labels[2].landmark_id[0], 7);
  EXPECT_EQ(dec.labels[2].landmark_id[1], +feature_labels_t::UNKNOWN);  // own barcode
  for (size_t i = 0; i < dec.features.size(); ++i) EXPECT_EQ(dec.features[i].seq, static_cast<int64_t>(i));

  ASSERT_EQ(dec.maps.size(), 1u);
  ASSERT_EQ(dec.maps[0].num_landmarks, 2);
  EXPECT_EQ(dec.maps[0].landmarks[0].id, 6);
  EXPECT_EQ(dec.maps[0].landmarks[0].kind, +feature_t::KIND_VERTICAL_LINE);
  EXPECT_DOUBLE_EQ(dec.maps[0].landmarks[1].position_m[0], -1.0);
  EXPECT_EQ(dec.truth.size(), 31u);

  // Events in utime order; the log timestamp is the utime; map first.
  for (size_t i = 1; i < log.events.size(); ++i) EXPECT_LE(log.events[i - 1].utime, log.events[i].utime);
  EXPECT_EQ(log.events.front().channel, channels::kGroundTruthMap);

  // Odometry: (0,0,0) at 100.0, 0.5 m at 100.5, 1 m at 101.0, then an arc of radius 1 over 0.5 rad.
  ASSERT_EQ(dec.odometry.size(), 4u);
  EXPECT_DOUBLE_EQ(dec.odometry[0].x_m, 0.0);
  EXPECT_NEAR(dec.odometry[1].x_m, 0.5, 1e-12);
  EXPECT_NEAR(dec.odometry[2].x_m, 1.0, 1e-12);
  EXPECT_NEAR(dec.odometry[3].x_m, 1.0 + std::sin(0.5), 1e-12);
  EXPECT_NEAR(dec.odometry[3].y_m, 1.0 - std::cos(0.5), 1e-12);
  EXPECT_NEAR(dec.odometry[3].theta_rad, 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(dec.odometry[2].v_mps, 0.5);
  EXPECT_DOUBLE_EQ(dec.odometry[2].omega_radps, 0.5);

  // Start pose: the truth at the first frame within the odometry (100.2 s).
  ASSERT_TRUE(r.start_pose.has_value());
  EXPECT_EQ(r.start_frame_utime, 100'200'000);
  EXPECT_NEAR(r.start_pose->x_m, 2.3, 1e-9);
  EXPECT_NEAR(r.start_pose->y_m, 3.0, 1e-9);
  EXPECT_NEAR(r.start_pose->theta_rad, 0.1, 1e-9);
  EXPECT_NE(r.describe().find("1 unknown barcodes"), std::string::npos);
}

TEST(MrclamImport, DropRobotSightingsIsCounted) {
  t::TempDir d;
  writeDataset(d);
  mrclam::ImportOptions o;
  o.drop_robot_sightings = true;
  const auto log = mrclam::importRobot(d.path(), o);
  EXPECT_EQ(log.report.robot_sightings, 1);
  EXPECT_EQ(log.report.robot_sightings_dropped, 1);
  EXPECT_EQ(log.report.features, 4);
  const Decoded dec = decode(log);
  EXPECT_EQ(dec.features[0].num_features, 1);
  EXPECT_EQ(dec.labels[0].landmark_id[0], 6);
}

TEST(MrclamImport, FeaturesCarryNoAppearance) {
  t::TempDir d;
  writeDataset(d);
  const Decoded dec = decode(mrclam::importRobot(d.path(), mrclam::ImportOptions{}));
  ASSERT_EQ(dec.features.size(), 3u);
  ASSERT_EQ(dec.features[0].features.size(), 2u);
  for (const auto& fr : dec.features) {
    for (const feature_t& f : fr.features) {  // no image: the filter sees bearings only
      EXPECT_EQ(f.colour_a[0] + f.colour_a[1] + f.colour_a[2] + f.colour_b[0] + f.colour_b[1] + f.colour_b[2], 0.0f);
    }
  }
}

TEST(MrclamImport, TruthLandmarksForLocalisationInTheTrueMap) {
  t::TempDir d;
  writeDataset(d);
  const std::vector<slam::Landmark> L = mrclam::truthLandmarks(d.path());
  ASSERT_EQ(L.size(), 2u);
  EXPECT_EQ(L[0].id, 6u);
  EXPECT_EQ(L[0].kind, slam::LandmarkKind::kVerticalLine);
  EXPECT_DOUBLE_EQ(L[0].p_LinW_m.x(), 1.0);
  EXPECT_DOUBLE_EQ(L[0].p_LinW_m.y(), 2.0);
  EXPECT_NEAR(L[0].cov_LinW_m2(0, 0), 1e-6, 1e-18);  // the file's x std-dev 0.001 m
  EXPECT_NEAR(L[0].cov_LinW_m2(1, 1), 4e-6, 1e-18);
  EXPECT_DOUBLE_EQ(L[0].cov_LinW_m2(2, 2), 1.0);
  EXPECT_DOUBLE_EQ(L[0].cov_LinW_m2(0, 1), 0.0);
  EXPECT_EQ(L[1].id, 7u);
  EXPECT_DOUBLE_EQ(L[1].p_LinW_m.x(), -1.0);
  // A saved map the SLAM process loads back unchanged.
  runtime::SavedMap m;
  m.landmarks = L;
  runtime::saveMapAtomically(m, d.file("truth_map.yaml"));
  const runtime::SavedMap back = runtime::loadMap(d.file("truth_map.yaml"));
  ASSERT_EQ(back.landmarks.size(), 2u);
  EXPECT_EQ(back.landmarks[1].p_LinW_m, L[1].p_LinW_m);
  EXPECT_EQ(back.landmarks[1].cov_LinW_m2, L[1].cov_LinW_m2);
  // A malformed landmark file names file and line.
  t::writeMrclamFile(d.file("Landmark_Groundtruth.dat"), "6 1.0 2.0 0.001\n");
  EXPECT_NE(errorOf([&] { mrclam::truthLandmarks(d.path()); }).find("Landmark_Groundtruth.dat:5"), std::string::npos);
}

TEST(MrclamImport, MaxDurationCutsAndCounts) {
  t::TempDir d;
  writeDataset(d);
  mrclam::ImportOptions o;
  o.max_duration_s = 1.0;  // 100.0 .. 101.0
  const auto log = mrclam::importRobot(d.path(), o);
  EXPECT_EQ(log.report.frames, 2);
  EXPECT_EQ(log.report.odometry_messages, 3);
  // 1 odometry + 2 measurement + 19 truth rows (101.1 .. 102.9 s) after 101.0 s.
  EXPECT_EQ(log.report.outside_stretch, 1 + 2 + 19);
}

TEST(MrclamImport, StillFramesSkippedOnRequestAndCounted) {
  t::TempDir d;
  // Standing still until 101.0 s, then 1 m/s: frames at 100.2 (first, kept), 100.7 (still: left
  // out) and 101.5 (moved 0.5 m: kept).
  writeDataset(d, "100.0 0.0 0.0\n101.0 1.0 0.0\n102.0 0.0 0.0\n");
  mrclam::ImportOptions o;
  EXPECT_EQ(mrclam::importRobot(d.path(), o).report.frames, 3);  // default: every frame
  o.still_frame_m = 0.05;
  o.still_frame_rad = 0.05;
  const auto log = mrclam::importRobot(d.path(), o);
  EXPECT_EQ(log.report.frames, 2);
  EXPECT_EQ(log.report.frames_still_skipped, 1);
  const Decoded dec = decode(log);
  ASSERT_EQ(dec.features.size(), 2u);
  EXPECT_EQ(dec.features[1].utime, 101'500'000);
  EXPECT_EQ(dec.labels[1].features_seq, 1);
}

TEST(MrclamImport, MalformedFilesNameFileAndLine) {
  t::TempDir d;
  const std::string p = d.file("Robot1_Odometry.dat");
  auto odo = [&](const std::string& body) {
    t::writeMrclamFile(p, body);
    return errorOf([&] { mrclam::readOdometry(p, mrclam::DuplicateTimes::kError); });
  };
  // Missing column (line 6: 4 header lines, then two data lines).
  std::string e = odo("1.0 0.1 0.0\n2.0 0.1\n");
  EXPECT_NE(e.find(p + ":6:"), std::string::npos) << e;
  EXPECT_NE(e.find("missing column 3"), std::string::npos) << e;
  // Extra column.
  e = odo("1.0 0.1 0.0 7\n");
  EXPECT_NE(e.find(p + ":5:"), std::string::npos) << e;
  EXPECT_NE(e.find("extra column"), std::string::npos) << e;
  // Non-numeric and non-finite fields.
  e = odo("1.0 0.1 0.0\n2.0 abc 0.0\n");
  EXPECT_NE(e.find(p + ":6:"), std::string::npos) << e;
  EXPECT_NE(e.find("not a number: 'abc'"), std::string::npos) << e;
  e = odo("1.0 0.1 nan\n");
  EXPECT_NE(e.find(p + ":5:"), std::string::npos) << e;
  EXPECT_NE(e.find("not finite"), std::string::npos) << e;
  e = odo("1.0 0.1 0.0x\n");
  EXPECT_NE(e.find("not a number"), std::string::npos) << e;
  // Unsorted and duplicated times.
  e = odo("1.0 0.1 0.0\n3.0 0.1 0.0\n2.0 0.1 0.0\n");
  EXPECT_NE(e.find(p + ":7:"), std::string::npos) << e;
  EXPECT_NE(e.find("before the previous"), std::string::npos) << e;
  e = odo("1.0 0.1 0.0\n2.0 0.1 0.0\n2.0 0.2 0.0\n");
  EXPECT_NE(e.find(p + ":7:"), std::string::npos) << e;
  EXPECT_NE(e.find("duplicated time"), std::string::npos) << e;
  // Two times that round to one microsecond are one utime: a duplicate too (it slipped through).
  e = odo("1248444187.156 0.1 0.0\n1248444187.1560002 0.1 0.0\n");
  EXPECT_NE(e.find(p + ":6: duplicated time"), std::string::npos) << e;
  // A finite time beyond any utime (1e13 s overflowed the conversion to a negative utime).
  e = odo("1.0 0.1 0.0\n1e13 0.1 0.0\n");
  EXPECT_NE(e.find(p + ":6: time 10000000000000 s outside 0..4000000000 s"), std::string::npos) << e;
  e = odo("-1.0 0.1 0.0\n");
  EXPECT_NE(e.find(p + ":5: time -1 s outside"), std::string::npos) << e;
  // Empty: only the header, or nothing at all; a missing file.
  e = odo("");
  EXPECT_NE(e.find(p + ": no data lines (empty file)"), std::string::npos) << e;
  { std::ofstream(p).close(); }
  e = errorOf([&] { mrclam::readOdometry(p, mrclam::DuplicateTimes::kError); });
  EXPECT_NE(e.find("empty file"), std::string::npos) << e;
  e = errorOf([&] { mrclam::readOdometry(d.file("nope.dat"), mrclam::DuplicateTimes::kError); });
  EXPECT_NE(e.find("nope.dat: cannot open"), std::string::npos) << e;

  // Measurements: times may repeat (one frame) but not go back; the code must be an integer.
  const std::string m = d.file("Robot1_Measurement.dat");
  t::writeMrclamFile(m, "1.0 63 2.0 0.1\n1.0 81 2.0 0.2\n0.5 63 2.0 0.1\n");
  e = errorOf([&] { mrclam::readMeasurements(m); });
  EXPECT_NE(e.find(m + ":7:"), std::string::npos) << e;
  t::writeMrclamFile(m, "1.0 63 2.0 0.1\n1e300 63 2.0 0.1\n");
  e = errorOf([&] { mrclam::readMeasurements(m); });
  EXPECT_NE(e.find(m + ":6: time 1e+300 s outside"), std::string::npos) << e;
  t::writeMrclamFile(m, "1.0 63.5 2.0 0.1\n");
  e = errorOf([&] { mrclam::readMeasurements(m); });
  EXPECT_NE(e.find(m + ":5:"), std::string::npos) << e;
  EXPECT_NE(e.find("must be an integer"), std::string::npos) << e;
  // Barcodes and landmarks: duplicates refused.
  const std::string b = d.file("Barcodes.dat");
  t::writeMrclamFile(b, "1 5\n2 5\n");
  e = errorOf([&] { mrclam::readBarcodes(b); });
  EXPECT_NE(e.find(b + ":6: duplicated barcode 5"), std::string::npos) << e;
  const std::string l = d.file("Landmark_Groundtruth.dat");
  t::writeMrclamFile(l, "6 1 2 0 0\n6 1 2 0 0\n");
  e = errorOf([&] { mrclam::readLandmarks(l); });
  EXPECT_NE(e.find(l + ":6: duplicated subject 6"), std::string::npos) << e;
  // The import stops on the first bad file, naming it.
  writeDataset(d, "1.0 0.1 0.0\n1.0 0.1 0.0\n");
  e = errorOf([&] { mrclam::importRobot(d.path(), {}); });
  EXPECT_NE(e.find("Robot1_Odometry.dat:6: duplicated time"), std::string::npos) << e;
}

// Finite values far beyond anything physical (1e308 m/s, which integrates to an infinite pose; a
// sigma of 1e200, an infinite truth covariance) and a negative sigma are each refused where they are
// read, naming file, line and range.
TEST(MrclamImport, ValuesBeyondPhysicalBoundsNameFileLineAndRange) {
  t::TempDir d;
  const std::string p = d.file("Robot1_Odometry.dat");
  auto odo = [&](const std::string& body) {
    t::writeMrclamFile(p, body);
    return errorOf([&] { mrclam::readOdometry(p, mrclam::DuplicateTimes::kError); });
  };
  std::string e = odo("1.0 0.1 0.0\n2.0 1e308 0.0\n");
  EXPECT_NE(e.find(p + ":6: column 'forward velocity [m/s]' is 1e+308, outside -100..100"), std::string::npos) << e;
  e = odo("1.0 0.1 -101\n");
  EXPECT_NE(e.find(p + ":5: column 'angular velocity [rad/s]' is -101, outside -100..100"), std::string::npos) << e;
  EXPECT_EQ(odo("1.0 100 -100\n"), "");  // the bounds themselves are accepted

  const std::string g = d.file("Robot1_Groundtruth.dat");
  auto truth = [&](const std::string& body) {
    t::writeMrclamFile(g, body);
    return errorOf([&] { mrclam::readGroundtruth(g, mrclam::DuplicateTimes::kError); });
  };
  e = truth("1.0 2e6 0 0\n");
  EXPECT_NE(e.find(g + ":5: column 'x [m]' is 2000000, outside -1000000..1000000"), std::string::npos) << e;
  e = truth("1.0 0 -1e300 0\n");
  EXPECT_NE(e.find(g + ":5: column 'y [m]'"), std::string::npos) << e;
  e = truth("1.0 0 0 1e20\n");
  EXPECT_NE(e.find(g + ":5: column 'orientation [rad]' is 1e+20, outside -100..100"), std::string::npos) << e;

  const std::string m = d.file("Robot1_Measurement.dat");
  auto meas = [&](const std::string& body) {
    t::writeMrclamFile(m, body);
    return errorOf([&] { mrclam::readMeasurements(m); });
  };
  e = meas("1.0 63 2.0 0.1\n2.0 63 -0.5 0.1\n");
  EXPECT_NE(e.find(m + ":6: column 'range [m]' is -0.5, outside 0..1000000"), std::string::npos) << e;
  e = meas("1.0 63 2.0 1e300\n");
  EXPECT_NE(e.find(m + ":5: column 'bearing [rad]' is 1e+300, outside -100..100"), std::string::npos) << e;
  // 4096 measurements at one time make one frame; the 4097th is refused at its own line.
  std::string rows;
  for (int k = 0; k < 4096; ++k) rows += "1.0 63 2.0 0.1\n";
  EXPECT_EQ(meas(rows + "2.0 63 2.0 0.1\n"), "");
  e = meas("0.5 63 2.0 0.1\n" + rows + "1.0 81 2.0 0.1\n");
  EXPECT_NE(e.find(m + ":4102: more than 4096 measurements at time 1 s (from line 6)"), std::string::npos) << e;

  const std::string l = d.file("Landmark_Groundtruth.dat");
  auto lms = [&](const std::string& body) {
    t::writeMrclamFile(l, body);
    return errorOf([&] { mrclam::readLandmarks(l); });
  };
  e = lms("6 1 2 1e200 0\n");
  EXPECT_NE(e.find(l + ":5: column 'x std-dev [m]' is 1e+200, outside 0..100"), std::string::npos) << e;
  e = lms("6 1 2 0 -0.001\n");
  EXPECT_NE(e.find(l + ":5: column 'y std-dev [m]' is -0.001, outside 0..100"), std::string::npos) << e;
  e = lms("6 1e7 2 0 0\n");
  EXPECT_NE(e.find(l + ":5: column 'x [m]'"), std::string::npos) << e;
  std::string many;
  for (int k = 0; k <= 100000; ++k) many += std::to_string(k) + " 1 2 0 0\n";
  e = lms(many);
  EXPECT_NE(e.find(l + ":100005: more than 100000 landmarks"), std::string::npos) << e;

  // Through the whole import: a ParseError naming the file and line, not a logic_error.
  writeDataset(d, "100.0 1.0 0.0\n100.5 1e308 0.0\n101.0 0.5 0.5\n");
  e = errorOf([&] { mrclam::importRobot(d.path(), {}); });
  EXPECT_NE(e.find("Robot1_Odometry.dat:6: column 'forward velocity [m/s]'"), std::string::npos) << e;
}

TEST(MrclamImport, AByteOrderMarkBeforeTheFirstLineIsNotData) {
  t::TempDir d;
  const std::string p = d.file("Robot1_Odometry.dat");
  std::ofstream(p) << "\xEF\xBB\xBF# a header comment\n1.0 0.1 0.0\n";
  mrclam::FileStats st;
  ASSERT_EQ(mrclam::readOdometry(p, mrclam::DuplicateTimes::kError, &st).size(), 1u);
  EXPECT_EQ(st.comment_lines, 1);
}

// Line ends of every kind: "\n", "\r\n" and a lone "\r" (old Mac files, which std::getline reads as
// one line: the header comment would hide every data line and the file would be "empty").
TEST(MrclamImport, EveryKindOfLineEndEndsALine) {
  t::TempDir d;
  const std::string p = d.file("Robot1_Odometry.dat");
  for (const std::string& eol : {std::string("\n"), std::string("\r\n"), std::string("\r")}) {
    std::ofstream(p) << "# header" << eol << "1.0 0.1 0.0" << eol << eol << "2.0 0.2 0.0" << eol << "3.0 0.3 0.0";
    mrclam::FileStats st;
    const auto v = mrclam::readOdometry(p, mrclam::DuplicateTimes::kError, &st);
    ASSERT_EQ(v.size(), 3u) << "line end " << (eol == "\r" ? "CR" : eol == "\n" ? "LF" : "CRLF");
    EXPECT_DOUBLE_EQ(v[2].v_mps, 0.3);
    EXPECT_EQ(st.lines, 5);
    EXPECT_EQ(st.comment_lines, 1);
    EXPECT_EQ(st.blank_lines, 1);
  }
  // A malformed line is named by its number with CR-only line ends too.
  std::ofstream(p) << "# header\r1.0 0.1 0.0\r2.0 x 0.0\r";
  const std::string e = errorOf([&] { mrclam::readOdometry(p, mrclam::DuplicateTimes::kError); });
  EXPECT_NE(e.find(p + ":3: column 2"), std::string::npos) << e;
}

TEST(MrclamImport, DuplicatedTimesKeepLastIsCounted) {
  t::TempDir d;
  const std::string p = d.file("odo.dat");
  t::writeMrclamFile(p, "\n1.0 0.1 0.0\n2.0 0.1 0.0\n2.0 0.2 0.3\n3.0 0.1 0.0\n   \n");
  mrclam::FileStats st;
  const auto v = mrclam::readOdometry(p, mrclam::DuplicateTimes::kKeepLast, &st);
  ASSERT_EQ(v.size(), 3u);
  EXPECT_DOUBLE_EQ(v[1].v_mps, 0.2);  // the later line kept
  EXPECT_EQ(st.duplicates_replaced, 1);
  ASSERT_EQ(st.duplicate_lines.size(), 1u);
  EXPECT_EQ(st.duplicate_lines[0], 8);
  EXPECT_EQ(st.blank_lines, 2);
  EXPECT_EQ(st.data_lines, 4);
  EXPECT_EQ(st.lines, 10);
  EXPECT_NE(mrclam::describe(st).find("1 duplicated times, the later line kept (lines 8)"), std::string::npos);
}

TEST(MrclamImport, BadOptionsRefused) {
  mrclam::ImportOptions o;
  o.bearing_sigma_rad = 0.0;
  EXPECT_EQ(o.validate(), "bearing sigma must be in (0, 1) rad, got 0.000000");
  o = {};
  o.robot = 0;
  EXPECT_EQ(o.validate(), "robot must be in 1..99, got 0");
  EXPECT_THROW(mrclam::importRobot("/nonexistent", o), std::invalid_argument);
}

}  // namespace
