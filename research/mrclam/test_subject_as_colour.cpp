// research_mrclam_subject_as_colour on a tiny MRCLAM-format dataset the test writes and imports with
// omnislam-import-mrclam: each feature's colour_a[0] becomes its barcode's subject (a landmark, another
// robot, 0 for a code of no subject), nothing else changes, and its input is never overwritten.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "mrclam_files.h"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/odometry_t.hpp"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

/// Robot 1; frame 1 at 100.2: landmark 6 (barcode 63) and robot 2 (barcode 14); frame 2 at 100.7: the
/// unknown code 43; frame 3 at 101.5: landmark 7 (barcode 81) and the robot's own barcode 5.
void writeDataset(const t::TempDir& d) {
  t::writeMrclamFile(d.file("Barcodes.dat"), "1 5\n2 14\n6 63\n7 81\n");
  t::writeMrclamFile(d.file("Landmark_Groundtruth.dat"), "6 1.0 2.0 0.001 0.002\n7 -1.0 0.5 0.001 0.001\n");
  t::writeMrclamFile(d.file("Robot1_Odometry.dat"), "100.0 1.0 0.0\n100.5 1.0 0.0\n101.0 0.5 0.5\n102.0 0.0 0.0\n");
  std::string truth;
  for (int k = 0; k <= 30; ++k) {
    char line[128];
    std::snprintf(line, sizeof line, "%.3f %.4f 3.0 0.1\n", 99.9 + 0.1 * k, 2.0 + 0.1 * k);
    truth += line;
  }
  t::writeMrclamFile(d.file("Robot1_Groundtruth.dat"), truth);
  t::writeMrclamFile(d.file("Robot1_Measurement.dat"),
                     "100.2 63 3.0 0.25\n100.2 14 2.0 -0.30\n100.7 43 4.0 0.1\n101.5 81 2.5 -0.5\n101.5 5 1.0 0.05\n");
}

}  // namespace

TEST(ResearchMrclam, SubjectAsColourGivesEachFeatureItsBarcodesSubject) {
  t::TempDir d;
  writeDataset(d);
  const std::string in = d.file("in.lcm"), out = d.file("out.lcm");
  auto r = t::run({t::binPath("omnislam-import-mrclam"), d.path(), "--robot", "1", "--out", in}, 60.0);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = t::run({t::binPath("research_mrclam_subject_as_colour"), d.path(), in, out}, 60.0);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto before = lcmio::readChannel<features_t>(in, channels::kOmniFeatures);
  const auto after = lcmio::readChannel<features_t>(out, channels::kOmniFeatures);
  ASSERT_EQ(after.size(), 3u);
  ASSERT_EQ(before.size(), 3u);
  ASSERT_EQ(after[0].features.size(), 2u);
  ASSERT_EQ(after[2].features.size(), 2u);
  EXPECT_EQ(after[0].features[0].colour_a[0], 6.0f);  // landmark 6
  EXPECT_EQ(after[0].features[1].colour_a[0], 2.0f);  // robot 2
  EXPECT_EQ(after[1].features[0].colour_a[0], 0.0f);  // code 43: no subject
  EXPECT_EQ(after[2].features[0].colour_a[0], 7.0f);  // landmark 7
  EXPECT_EQ(after[2].features[1].colour_a[0], 1.0f);  // the robot's own barcode
  for (size_t k = 0; k < after.size(); ++k) {
    for (size_t i = 0; i < after[k].features.size(); ++i) {
      feature_t f = after[k].features[i];
      EXPECT_EQ(f.colour_a[1] + f.colour_a[2], 0.0f);
      f.colour_a[0] = 0.0f;
      EXPECT_EQ(f.azimuth_rad, before[k].features[i].azimuth_rad);
    }
  }
  // Every other channel is copied: the same number of labels and odometry messages.
  EXPECT_EQ(lcmio::readChannel<feature_labels_t>(out, channels::kGroundTruthFeatureLabels).size(), 3u);
  EXPECT_EQ(lcmio::readChannel<odometry_t>(out, channels::kOdometry).size(),
            lcmio::readChannel<odometry_t>(in, channels::kOdometry).size());
}

TEST(ResearchMrclam, SubjectAsColourRefusesToOverwriteItsInput) {
  t::TempDir d;
  writeDataset(d);
  const std::string in = d.file("in.lcm");
  ASSERT_EQ(t::run({t::binPath("omnislam-import-mrclam"), d.path(), "--robot", "1", "--out", in}, 60.0).exit_code, 0);
  const auto r = t::run({t::binPath("research_mrclam_subject_as_colour"), d.path(), in, in}, 60.0);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("is the input log"), std::string::npos) << r.output;
}
