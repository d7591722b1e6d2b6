// omnislam-calibrate end to end on the shared catadioptric images (opencv_contrib's omnidir sample
// set, 9 views of a 6 x 9 inner-corner board; data-gated): the rms reprojection error is at most
// 0.5 px, the written file is read as an OpenCV omnidir calibration, builds a detector through
// makeDetector with `camera.model: auto`, and omnislam-features runs on the images with it.
// Also: bad flags and too few boards are refused with exit code 2 and a message, never a crash.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>

#include "detectors.h"
#include "omnislam/config/yaml_node.h"
#include "omnislam/vision/calibration_files.h"
#include "datasets.h"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

const std::string kCatadioptric = t::datasetPath("omni-images/opencv-omnidir-catadioptric");

TEST(Calibrate, CatadioptricSampleSetCalibratesAndLoads) {
  if (!std::filesystem::is_directory(kCatadioptric))
    GTEST_SKIP() << "dataset absent: " << kCatadioptric << " (set OMNISLAM_DATASETS)";
  t::TempDir dir;
  const std::string out = dir.file("omni.yaml");
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = t::run({t::binPath("omnislam-calibrate"), "--images", kCatadioptric, "--corners", "6x9", "--square-m",
                         "1", "--model", "omnidir", "--out", out, "--annotate", dir.file("annotated")},
                        240.0);
  std::cout << "omnislam-calibrate took "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s\n";
  ASSERT_EQ(r.exit_code, 0) << r.output;
  cv::FileStorage fs(out, cv::FileStorage::READ);
  ASSERT_TRUE(fs.isOpened());
  const double rms = fs["rms"];
  EXPECT_GT(rms, 0.0);
  EXPECT_LE(rms, 0.5) << r.output;
  EXPECT_EQ(static_cast<int>(fs["image_width"]), 1280);
  EXPECT_EQ(static_cast<int>(fs["image_height"]), 960);
  EXPECT_EQ(vision::readCalibrationFile(out).format, vision::CalibrationFormat::kOpencvOmnidir);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.file("annotated")), {}), 9);

  const std::string cfg = dir.file("features.yaml");
  std::ofstream(cfg) << "detector: ceiling_lights\ncamera:\n  model: auto\n  file: omni.yaml\n  optics: catadioptric\n"
                        "  mounting: {z_m: 1.0}\n";
  const auto det = features::makeDetector(config::Node::loadFile(cfg));
  EXPECT_NE(det->describe().find("OpenCV omnidir (Mei)"), std::string::npos) << det->describe();
  const auto f = t::run({t::binPath("omnislam-features"), "--config", cfg, "--images", kCatadioptric}, 120.0);
  EXPECT_EQ(f.exit_code, 0) << f.output;
}

TEST(Calibrate, BadInputIsRefusedWithAMessage) {
  if (!std::filesystem::is_directory(kCatadioptric))
    GTEST_SKIP() << "dataset absent: " << kCatadioptric << " (set OMNISLAM_DATASETS)";
  t::TempDir dir;
  // Two views with the board and a blank image (links and a written image, for a quick run).
  const std::string few = dir.file("few"), mixed = dir.file("mixed"), empty = dir.file("empty");
  for (const std::string& d : {few, mixed, empty}) std::filesystem::create_directory(d);
  for (const char* f : {"1.jpg", "2.jpg"}) std::filesystem::create_symlink(kCatadioptric + "/" + f, few + "/" + f);
  cv::imwrite(few + "/0_blank.png", cv::Mat(960, 1280, CV_8U, cv::Scalar(128)));
  std::filesystem::create_symlink(kCatadioptric + "/1.jpg", mixed + "/1.jpg");
  cv::imwrite(mixed + "/2_small.png", cv::Mat(10, 10, CV_8U, cv::Scalar(128)));
  const std::string bin = t::binPath("omnislam-calibrate"), out = dir.file("a.yaml");
  struct Case {
    std::vector<std::string> args;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {{"--images", few, "--square-m", "1", "--out", out},
       "--corners COLSxROWS (inner corners) or --squares COLSxROWS"},
      {{"--images", few, "--corners", "6x9", "--squares", "7x10", "--square-m", "1", "--out", out}, "excludes"},
      {{"--images", few, "--corners", "6by9", "--square-m", "1", "--out", out}, "'6by9' is not COLSxROWS"},
      {{"--images", few, "--corners", "1x9", "--square-m", "1", "--out", out}, "must be in [2, 100]"},
      {{"--images", few, "--squares", "2x9", "--square-m", "1", "--out", out}, "must be in [3, 101]"},
      {{"--images", few, "--corners", "6x9", "--square-m", "nan", "--out", out}, "--square-m"},
      {{"--images", few, "--corners", "6x9", "--square-m", "1", "--model", "pinhole", "--out", out}, "--model"},
      {{"--images", few, "--corners", "6x9", "--square-m", "1", "--out", out, "--min-boards", "2"}, "--min-boards"},
      {{"--images", empty, "--corners", "6x9", "--square-m", "1", "--out", out}, "holds no image files"},
      {{"--images", dir.file("absent"), "--corners", "6x9", "--square-m", "1", "--out", out}, "absent"},
      {{"--images", mixed, "--corners", "6x9", "--square-m", "1", "--out", out}, "one camera, one image size"},
      {{"--images", few, "--corners", "6x9", "--square-m", "1", "--out", out},
       "boards found in 2 of 3 images, fewer than --min-boards 5; no board of 6x9 inner corners in: 0_blank.png"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> argv{bin};
    argv.insert(argv.end(), c.args.begin(), c.args.end());
    const auto r = t::run(argv, 120.0);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << r.output;
  }
  EXPECT_FALSE(std::filesystem::exists(out)) << "nothing is written when the calibration is refused";
}

}  // namespace
