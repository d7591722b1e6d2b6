// The camera section of the features config with calibration files (procs/features/detectors.cpp):
// `model: auto` and the explicit formats, `optics`, the image size when the file has none, Kalibr's
// camera choice, roll / pitch in the mounting and the vertical-line detector's refusal of a tilted
// camera; also roll / pitch in a world file and the lights renderer. Every refusal names the key.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <cmath>
#include <fstream>
#include <functional>

#include "../support/proc_util.h"
#include "detectors.h"
#include "omnislam/config/world_config.h"
#include "omnislam/config/yaml_node.h"
#include "omnislam/vision/render_lights.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

/// An omnidir calibration as OpenCV's sample writes it (no image size), 1280 x 960 camera.
void writeOmnidir(const std::string& path) {
  cv::FileStorage fs(path, cv::FileStorage::WRITE);
  fs << "camera_matrix" << cv::Mat(cv::Matx33d(386.4, 0.0, 629.1, 0.0, 388.6, 433.3, 0.0, 0.0, 1.0));
  fs << "distortion_coefficients" << (cv::Mat_<double>(1, 4) << -0.06, 0.013, 0.0, 0.0);
  fs << "xi" << 0.94;
}

/// The ConfigError message of building the detector of `yaml` (a file in dir).
std::string errorOf(const t::TempDir& dir, const std::string& yaml) {
  const std::string path = dir.file("features.yaml");
  std::ofstream(path) << yaml;
  try {
    features::makeDetector(config::Node::loadFile(path));
  } catch (const config::ConfigError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    return m;
  }
  ADD_FAILURE() << "no ConfigError for\n" << yaml;
  return {};
}

std::unique_ptr<features::Detector> detectorOf(const t::TempDir& dir, const std::string& yaml) {
  const std::string path = dir.file("features.yaml");
  std::ofstream(path) << yaml;
  return features::makeDetector(config::Node::loadFile(path));
}

const std::string kLights = "detector: ceiling_lights\n";
const std::string kLines = "detector: vertical_lines\nvertical_lines: {r_min_px: 100, r_max_px: 400}\n";

TEST(FeaturesCameraConfig, AutoAndExplicitFormats) {
  t::TempDir dir;
  writeOmnidir(dir.file("omni.yaml"));
  const std::string cam =
      "  file: omni.yaml\n  optics: catadioptric\n  width_px: 1280\n  height_px: 960\n"
      "  mounting: {z_m: 1.0}\n";
  for (const char* model : {"auto", "opencv_omnidir"}) {
    const auto det = detectorOf(dir, kLights + "camera:\n  model: " + model + "\n" + cam);
    EXPECT_NE(det->describe().find("OpenCV omnidir (Mei) calibration"), std::string::npos) << det->describe();
    EXPECT_NE(det->describe().find("catadioptric"), std::string::npos) << det->describe();
    // 1280 x 960, from the config: images of another size are refused.
    EXPECT_FALSE(det->check(cv::Mat(960, 1280, CV_8U, cv::Scalar(0))));
    EXPECT_TRUE(det->check(cv::Mat(480, 640, CV_8U, cv::Scalar(0))));
  }
  // The lines detector takes its panorama centre from the calibration's principal point.
  const auto lines = detectorOf(dir, kLines + "camera:\n  model: auto\n" + cam);
  EXPECT_NE(lines->describe().find("panorama centre (629.1, 433.3)"), std::string::npos) << lines->describe();
  // The example: the omnidir file given as OCamCalib names the format.
  const std::string m = errorOf(dir, kLights + "camera:\n  model: ocamcalib\n" + cam);
  EXPECT_NE(m.find("key 'camera.file'"), std::string::npos) << m;
  EXPECT_NE(m.find("is an OpenCV omnidir (Mei) FileStorage file, not an OCamCalib calib_results.txt"),
            std::string::npos)
      << m;
}

TEST(FeaturesCameraConfig, RefusalsNameTheKey) {
  t::TempDir dir;
  writeOmnidir(dir.file("omni.yaml"));
  const std::string head = kLights + "camera:\n  model: auto\n  file: omni.yaml\n";
  const std::string mount = "  mounting: {z_m: 1.0}\n";
  struct Case {
    std::string yaml, expect;
  };
  const std::vector<Case> cases = {
      {head + "  optics: catadioptric\n" + mount,
       "omni.yaml' states no image size: set camera.width_px and camera.height_px"},
      {head + "  width_px: 1280\n  height_px: 960\n" + mount,
       "key 'camera.optics' is required for an OpenCV omnidir (Mei) FileStorage file: catadioptric"},
      {head + "  optics: mirror\n  width_px: 1280\n  height_px: 960\n" + mount, "key 'camera.optics'"},
      {head + "  optics: dioptric\n  width_px: 1280\n  height_px: 960\n  min_radius_px: 10\n" + mount,
       "key 'camera.min_radius_px' is not read for model 'auto'"},
      {head + "  optics: dioptric\n  width_px: 1280\n  height_px: 960\n  kalibr_camera: cam1\n" + mount,
       "key 'camera.kalibr_camera' is for Kalibr files"},
      {kLights + "camera:\n  model: auto\n  file: absent.yaml\n  optics: dioptric\n" + mount,
       "key 'camera.file' "},  // the key, then the path: "'/dir/absent.yaml' does not exist"
      {kLights + "camera:\n  model: auto\n  file: absent.yaml\n  optics: dioptric\n" + mount,
       "absent.yaml' does not exist"},
      {head + "  optics: dioptric\n  width_px: 1280\n  height_px: 960\n  mounting: {z_m: 1.0, pitch_deg: 91}\n",
       "key 'camera.mounting.pitch_deg'"},
      {head + "  optics: dioptric\n  width_px: 1280\n  height_px: 960\n  mounting: {z_m: 1.0, roll_deg: -181}\n",
       "key 'camera.mounting.roll_deg'"},
  };
  for (const Case& c : cases) {
    const std::string m = errorOf(dir, c.yaml);
    EXPECT_NE(m.find(c.expect), std::string::npos) << c.yaml << "\n-> " << m;
  }
}

TEST(FeaturesCameraConfig, KalibrCameraAndSizeAgreement) {
  t::TempDir dir;
  std::ofstream(dir.file("camchain.yaml"))
      << "cam0:\n  camera_model: pinhole\n  distortion_model: equidistant\n  distortion_coeffs: [0.01, 0, 0, 0]\n"
         "  intrinsics: [150, 150, 320, 240]\n  resolution: [640, 480]\n"
         "cam1:\n  camera_model: eucm\n  distortion_model: none\n  intrinsics: [0.6, 1.1, 200, 200, 330, 250]\n"
         "  resolution: [660, 500]\n";
  const std::string head = kLights + "camera:\n  model: kalibr\n  file: camchain.yaml\n  optics: dioptric\n";
  const auto det0 = detectorOf(dir, head + "  mounting: {z_m: 1.0}\n");
  EXPECT_NE(det0->describe().find("Kalibr cam0 (pinhole + equidistant)"), std::string::npos) << det0->describe();
  EXPECT_FALSE(det0->check(cv::Mat(480, 640, CV_8U, cv::Scalar(0))));
  const auto det1 = detectorOf(dir, head + "  kalibr_camera: cam1\n  mounting: {z_m: 1.0}\n");
  EXPECT_FALSE(det1->check(cv::Mat(500, 660, CV_8U, cv::Scalar(0))));
  const std::string m = errorOf(dir, head + "  width_px: 640\n  height_px: 400\n  mounting: {z_m: 1.0}\n");
  EXPECT_NE(m.find("key 'camera.height_px' is 400 but '"), std::string::npos) << m;
  EXPECT_NE(m.find("camchain.yaml' says 480"), std::string::npos) << m;
}

TEST(FeaturesCameraConfig, MountingRollPitch) {
  t::TempDir dir;
  writeOmnidir(dir.file("omni.yaml"));
  const std::string cam =
      "camera:\n  model: auto\n  file: omni.yaml\n  optics: dioptric\n  width_px: 1280\n"
      "  height_px: 960\n";
  const auto det =
      detectorOf(dir, kLights + cam + "  mounting: {z_m: 1.0, yaw_deg: 10, pitch_deg: 20, roll_deg: -30}\n");
  EXPECT_DOUBLE_EQ(det->mounting().yaw_rad, deg2rad(10.0));
  EXPECT_DOUBLE_EQ(det->mounting().pitch_rad, deg2rad(20.0));
  EXPECT_DOUBLE_EQ(det->mounting().roll_rad, deg2rad(-30.0));
  // Vertical lines: 0.5 deg of tilt is accepted, more is refused naming pitch_deg and roll_deg.
  EXPECT_NO_THROW(detectorOf(dir, kLines + cam + "  mounting: {z_m: 1.0, pitch_deg: 0.3, roll_deg: 0.3}\n"));
  const std::string m = errorOf(dir, kLines + cam + "  mounting: {z_m: 1.0, pitch_deg: 0.4, roll_deg: 0.4}\n");
  EXPECT_NE(m.find("key 'camera.mounting.pitch_deg' and 'roll_deg' tilt the optical axis 0.56"), std::string::npos)
      << m;
  EXPECT_NE(m.find("vertical_lines needs at most 0.5 deg"), std::string::npos) << m;
  EXPECT_THROW(features::verticalLineOptions(
                   config::Node::loadString(kLines + "camera: {model: centre_only, width_px: 640, height_px: 480, "
                                                     "mounting: {z_m: 1, roll_deg: 2}}\n",
                                            "lines.yaml")),
               config::ConfigError);
}

TEST(FeaturesCameraConfig, WorldMountingRollPitch) {
  std::string hall = t::readFile(t::sourcePath("config/worlds/sports_hall.yaml"));
  const size_t yaw = hall.find("yaw_deg:", hall.find("mounting:"));
  ASSERT_NE(yaw, std::string::npos);
  hall.insert(yaw, "pitch_deg: 5.0\n    roll_deg: -2.0\n    ");
  const sim::World w = config::parseWorld(config::Node::loadString(hall, "hall.yaml"));
  EXPECT_DOUBLE_EQ(w.camera.mounting.pitch_rad, deg2rad(5.0));
  EXPECT_DOUBLE_EQ(w.camera.mounting.roll_rad, deg2rad(-2.0));
  // The lights renderer takes the whole rotation: world <- robot (yaw of the pose) <- camera.
  const Pose2 T{3.0, 1.0, 0.7};
  const Eigen::Matrix3d R = vision::cameraInWorld(T, w.camera.mounting).R_WfromC;
  const Eigen::Matrix3d expect = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                                 camera::rotationCameraToRobot(w.camera.mounting);
  EXPECT_LT((R - expect).norm(), 1e-15);
  EXPECT_NEAR(std::acos((R * Eigen::Vector3d::UnitZ()).z()), deg2rad(std::hypot(5.0, 2.0)), deg2rad(0.05));
}

}  // namespace
