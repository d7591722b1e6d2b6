// The calibration file readers (calibration_files.h) on small files the tests write: OpenCV omnidir
// and fisheye FileStorage files in YAML and XML (as cv::FileStorage writes them), Kalibr
// camchain.yaml of each supported model, OCamCalib calib_results.txt; format detection; and
// malformed files, each refused with one line naming the file and what is wrong.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <fstream>
#include <functional>

#include "../support/proc_util.h"
#include "omnislam/config/yaml_node.h"
#include "omnislam/vision/calibration_files.h"

using namespace omnislam;
using namespace omnislam::vision;
namespace t = omnislam::testing;

namespace {

const cv::Matx33d kK(400.5, 0.25, 640.1, 0.0, 401.5, 480.2, 0.0, 0.0, 1.0);

/// An omnidir file with the keys omni_calibration.cpp (opencv_contrib, ccalib samples) writes.
void writeOmnidir(const std::string& path, bool with_size) {
  cv::FileStorage fs(path, cv::FileStorage::WRITE);
  fs << "calibration_time"
     << "Thu Nov 26 2026";
  fs << "nFrames" << 9 << "flags" << 0;
  fs << "camera_matrix" << cv::Mat(kK);
  fs << "distortion_coefficients" << (cv::Mat_<double>(1, 4) << -0.3, 0.1, 1e-3, -2e-3);
  fs << "xi" << 0.96;
  fs << "used_imgs"
     << "["
     << "1.jpg"
     << "2.jpg"
     << "]";
  fs << "rms" << 0.4;
  if (with_size) fs << "image_width" << 1280 << "image_height" << 960;
}

void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

/// The ConfigError message of f(); fails the test when nothing is thrown or it spans lines.
std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const config::ConfigError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    return m;
  }
  ADD_FAILURE() << "no ConfigError";
  return {};
}

const char* const kOcamText =
    "#polynomial coefficients for the DIRECT mapping function (ocam_model.ss in MATLAB). These are used by "
    "cam2world\n\n"
    "5 -2.063866e+02 0.000000e+00 2.165610e-03 -4.495456e-06 1.810639e-08\n\n"
    "#polynomial coefficients for the inverse mapping function (ocam_model.invpol in MATLAB).\n\n"
    "3 293.05 151.54 -11.13\n\n#center: \"row\" and \"column\", starting from 0 (C convention)\n\n"
    "241.019976 385.783141\n\n#affine parameters \"c\", \"d\", \"e\"\n\n0.998881 -0.042038 0.045079\n\n"
    "#image size: \"height\" and \"width\"\n\n480 748\n";

TEST(CalibrationFiles, OmnidirYamlAndXmlAsOpenCvWritesThem) {
  t::TempDir dir;
  for (const std::string ext : {".yaml", ".xml"}) {
    const std::string path = dir.file("omni" + ext);
    writeOmnidir(path, false);
    const CameraCalibration c = readCalibrationFile(path);
    EXPECT_EQ(c.format, CalibrationFormat::kOpencvOmnidir) << ext;
    const auto& m = std::get<MeiIntrinsics>(c.intrinsics);
    EXPECT_EQ(m.fx_px, 400.5);
    EXPECT_EQ(m.fy_px, 401.5);
    EXPECT_EQ(m.cx_px, 640.1);
    EXPECT_EQ(m.cy_px, 480.2);
    EXPECT_EQ(m.skew_px, 0.25);
    EXPECT_EQ(m.xi, 0.96);
    EXPECT_EQ(m.k1, -0.3);
    EXPECT_EQ(m.k2, 0.1);
    EXPECT_EQ(m.p1, 1e-3);
    EXPECT_EQ(m.p2, -2e-3);
    EXPECT_EQ(c.width_px, 0) << "the sample writes no image size";
    EXPECT_EQ(c.height_px, 0);
    // Read as what it is, explicitly.
    EXPECT_EQ(readCalibrationFile(path, {CalibrationFormat::kOpencvOmnidir, ""}).format,
              CalibrationFormat::kOpencvOmnidir);
  }
  const std::string sized = dir.file("sized.yaml");
  writeOmnidir(sized, true);
  const CameraCalibration c = readCalibrationFile(sized);
  EXPECT_EQ(c.width_px, 1280);
  EXPECT_EQ(c.height_px, 960);
}

TEST(CalibrationFiles, FisheyeFileHasNoXi) {
  t::TempDir dir;
  for (const std::string ext : {".yml", ".xml"}) {
    const std::string path = dir.file("fisheye" + ext);
    {
      cv::FileStorage fs(path, cv::FileStorage::WRITE);
      fs << "image_width" << 1280 << "image_height" << 800;
      fs << "camera_matrix" << cv::Mat(kK);
      fs << "distortion_coefficients" << (cv::Mat_<double>(4, 1) << 0.01, -0.02, 0.003, -0.0004);  // cv::fisheye: 4x1
    }
    const CameraCalibration c = readCalibrationFile(path);
    EXPECT_EQ(c.format, CalibrationFormat::kOpencvFisheye) << ext;
    const auto& k = std::get<KannalaBrandtIntrinsics>(c.intrinsics);
    EXPECT_EQ(k.fx_px, 400.5);
    EXPECT_EQ(k.skew_px, 0.25);
    EXPECT_EQ(k.k1, 0.01);
    EXPECT_EQ(k.k4, -0.0004);
    EXPECT_EQ(c.width_px, 1280);
    EXPECT_EQ(c.height_px, 800);
  }
}

TEST(CalibrationFiles, KalibrModels) {
  t::TempDir dir;
  const std::string path = dir.file("camchain.yaml");
  writeText(
      path,
      "cam0:\n  cam_overlaps: [1]\n  camera_model: omni\n  distortion_coeffs: [-0.28, 0.07, 0.0002, 1.7e-05]\n"
      "  distortion_model: radtan\n  intrinsics: [1.1, 458.6, 457.3, 367.2, 248.4]\n  resolution: [752, 480]\n"
      "  rostopic: /cam0/image_raw\n"
      "cam1:\n  T_cn_cnm1:\n  - [1.0, 0.0, 0.0, 0.1]\n  - [0.0, 1.0, 0.0, 0.0]\n  - [0.0, 0.0, 1.0, 0.0]\n"
      "  - [0.0, 0.0, 0.0, 1.0]\n  camera_model: pinhole\n  distortion_model: equidistant\n"
      "  distortion_coeffs: [0.01, 0.02, 0.03, 0.04]\n  intrinsics: [300, 301, 320, 240]\n  resolution: [640, 480]\n"
      "cam2:\n  camera_model: ds\n  distortion_model: none\n  distortion_coeffs: []\n"
      "  intrinsics: [-0.2, 0.6, 350, 351, 640, 400]\n  resolution: [1280, 800]\n"
      "cam3:\n  camera_model: eucm\n  distortion_model: none\n  intrinsics: [0.6, 1.1, 350, 351, 640, 400]\n"
      "cam4:\n  camera_model: omni\n  distortion_model: none\n  distortion_coeffs: []\n"
      "  intrinsics: [0.9, 300, 300, 320, 240]\n  resolution: [640, 480]\n");
  const CameraCalibration c0 = readCalibrationFile(path);  // the first camera
  EXPECT_EQ(c0.format, CalibrationFormat::kKalibr);
  const auto& m = std::get<MeiIntrinsics>(c0.intrinsics);
  EXPECT_EQ(m.xi, 1.1);
  EXPECT_EQ(m.fx_px, 458.6);
  EXPECT_EQ(m.fy_px, 457.3);
  EXPECT_EQ(m.cx_px, 367.2);
  EXPECT_EQ(m.cy_px, 248.4);
  EXPECT_EQ(m.k1, -0.28);
  EXPECT_EQ(m.p2, 1.7e-05);
  EXPECT_EQ(c0.width_px, 752);
  EXPECT_EQ(c0.height_px, 480);
  EXPECT_NE(c0.description.find("cam0"), std::string::npos) << c0.description;

  const auto k = std::get<KannalaBrandtIntrinsics>(readCalibrationFile(path, {std::nullopt, "cam1"}).intrinsics);
  EXPECT_EQ(k.fx_px, 300.0);
  EXPECT_EQ(k.cy_px, 240.0);
  EXPECT_EQ(k.k1, 0.01);
  EXPECT_EQ(k.k4, 0.04);
  const auto ds = std::get<DoubleSphereIntrinsics>(readCalibrationFile(path, {std::nullopt, "cam2"}).intrinsics);
  EXPECT_EQ(ds.xi, -0.2);
  EXPECT_EQ(ds.alpha, 0.6);
  EXPECT_EQ(ds.fx_px, 350.0);
  EXPECT_EQ(ds.cy_px, 400.0);
  const CameraCalibration c3 = readCalibrationFile(path, {CalibrationFormat::kKalibr, "cam3"});
  const auto eu = std::get<EucmIntrinsics>(c3.intrinsics);
  EXPECT_EQ(eu.alpha, 0.6);
  EXPECT_EQ(eu.beta, 1.1);
  EXPECT_EQ(eu.fy_px, 351.0);
  EXPECT_EQ(c3.width_px, 0) << "no resolution key: the size comes from the features config";
  const auto m4 = std::get<MeiIntrinsics>(readCalibrationFile(path, {std::nullopt, "cam4"}).intrinsics);
  EXPECT_EQ(m4.xi, 0.9);
  EXPECT_EQ(m4.k1, 0.0);
  EXPECT_EQ(m4.p2, 0.0);
}

TEST(CalibrationFiles, CameraModelsFromCalibrations) {
  t::TempDir dir;
  const std::string path = dir.file("camchain.yaml");
  writeText(path,
            "cam0:\n  camera_model: omni\n  distortion_model: radtan\n  distortion_coeffs: [-0.1, 0.01, 0.001, 0.0]\n"
            "  intrinsics: [0.9, 300, 301, 320, 240]\n  resolution: [640, 480]\n"
            "cam1:\n  camera_model: pinhole\n  distortion_model: equidistant\n  distortion_coeffs: [0.01, 0, 0, 0]\n"
            "  intrinsics: [150, 150, 320, 240]\n  resolution: [640, 480]\n"
            "cam2:\n  camera_model: ds\n  distortion_model: none\n  intrinsics: [-0.2, 0.6, 200, 200, 320, 240]\n"
            "cam3:\n  camera_model: eucm\n  distortion_model: none\n  intrinsics: [0.6, 1.1, 200, 200, 320, 240]\n"
            "cam4:\n  camera_model: ds\n  distortion_model: none\n  intrinsics: [1.5, 0.6, 200, 200, 320, 240]\n");
  const std::vector<std::pair<std::string, std::string>> expect = {
      {"cam0", "mei-unified"}, {"cam1", "kannala-brandt"}, {"cam2", "double-sphere"}, {"cam3", "eucm"}};
  for (const auto& [cam, name] : expect) {
    const CameraCalibration c = readCalibrationFile(path, {std::nullopt, cam});
    EXPECT_EQ(principalPointPx(c), Eigen::Vector2d(320, 240)) << cam;
    const auto lens = makeCalibratedCamera(c, camera::OcamOptics::kDioptric, 640, 480);
    const auto mirror = makeCalibratedCamera(c, camera::OcamOptics::kCatadioptric, 640, 480);
    EXPECT_EQ(lens->name(), name);
    EXPECT_EQ(mirror->name(), name + " (catadioptric)");
    EXPECT_EQ(lens->widthPx(), 640);
    EXPECT_EQ(lens->heightPx(), 480);
    // The principal point sees the optical axis: up through a lens, down (the camera) in a mirror.
    const auto up = lens->unproject({320.0, 240.0});
    const auto down = mirror->unproject({320.0, 240.0});
    ASSERT_TRUE(up && down) << cam;
    EXPECT_NEAR(up->z(), 1.0, 1e-12) << cam;
    EXPECT_NEAR(down->z(), -1.0, 1e-12) << cam;
    // Off the axis the mirror flips z only: same azimuth seen from below.
    const auto a = lens->unproject({400.0, 200.0});
    const auto b = mirror->unproject({400.0, 200.0});
    ASSERT_TRUE(a && b) << cam;
    EXPECT_NEAR((*b - Eigen::Vector3d(a->x(), a->y(), -a->z())).norm(), 0.0, 1e-12) << cam;
  }
  // A value the file format allows but the model refuses: named with the calibration.
  const CameraCalibration bad = readCalibrationFile(path, {std::nullopt, "cam4"});
  const std::string m = errorOf([&] { makeCalibratedCamera(bad, camera::OcamOptics::kDioptric, 640, 480); });
  EXPECT_NE(m.find("Kalibr cam4 (ds + none) of '" + path + "': "), std::string::npos) << m;
  EXPECT_NE(m.find("xi"), std::string::npos) << m;
  // OCamCalib: a Scaramuzza camera with the optics asked for.
  writeText(dir.file("calib_results.txt"), kOcamText);
  const CameraCalibration oc = readCalibrationFile(dir.file("calib_results.txt"));
  EXPECT_EQ(principalPointPx(oc), Eigen::Vector2d(385.783141, 241.019976));
  EXPECT_EQ(makeCalibratedCamera(oc, camera::OcamOptics::kCatadioptric, 748, 480)->name(), "scaramuzza-ocamcalib");
}

TEST(CalibrationFiles, OcamCalibByContent) {
  t::TempDir dir;
  const std::string path = dir.file("calib_results.txt");
  writeText(path, kOcamText);
  const CameraCalibration c = readCalibrationFile(path);
  EXPECT_EQ(c.format, CalibrationFormat::kOcamcalib);
  const auto& p = std::get<camera::ScaramuzzaParams>(c.intrinsics);
  EXPECT_EQ(p.pol.size(), 5u);
  EXPECT_EQ(p.xc_row_px, 241.019976);
  EXPECT_EQ(c.width_px, 748);
  EXPECT_EQ(c.height_px, 480);
}

TEST(CalibrationFiles, WrongFormatRequestedNamesTheFormatFound) {
  t::TempDir dir;
  const std::string omni = dir.file("omni.yaml");
  writeOmnidir(omni, false);
  // The example: an omnidir YAML given as OCamCalib.
  std::string m = errorOf([&] { readCalibrationFile(omni, {CalibrationFormat::kOcamcalib, ""}); });
  EXPECT_NE(m.find(omni), std::string::npos) << m;
  EXPECT_NE(m.find("is an OpenCV omnidir (Mei) FileStorage file, not an OCamCalib calib_results.txt: read it as "
                   "'opencv_omnidir' or 'auto'"),
            std::string::npos)
      << m;
  m = errorOf([&] { readCalibrationFile(omni, {CalibrationFormat::kOpencvFisheye, ""}); });
  EXPECT_NE(m.find("not an OpenCV fisheye FileStorage file"), std::string::npos) << m;
  const std::string ocam = dir.file("calib_results.txt");
  writeText(ocam, kOcamText);
  m = errorOf([&] { readCalibrationFile(ocam, {CalibrationFormat::kKalibr, ""}); });
  EXPECT_NE(m.find("is an OCamCalib calib_results.txt, not a Kalibr camchain.yaml"), std::string::npos) << m;
  m = errorOf([&] { readCalibrationFile(ocam, {CalibrationFormat::kOpencvOmnidir, ""}); });
  EXPECT_NE(m.find("is an OCamCalib calib_results.txt, not an OpenCV omnidir"), std::string::npos) << m;
}

TEST(CalibrationFiles, UnknownFormatListsTheAccepted) {
  t::TempDir dir;
  const std::string path = dir.file("notes.txt");
  writeText(path, "focal length about 300 px\n");
  std::string m = errorOf([&] { readCalibrationFile(path); });
  EXPECT_NE(m.find("'" + path + "': unknown calibration format; accepted: OpenCV FileStorage YAML/XML of cv::omnidir"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("Kalibr camchain.yaml"), std::string::npos) << m;
  EXPECT_NE(m.find("OCamCalib calib_results.txt"), std::string::npos) << m;
  writeText(path, "camera_matrix: [1, 0, 0]\nxi: 1\n");  // OpenCV keys, no FileStorage header
  m = errorOf([&] { readCalibrationFile(path); });
  EXPECT_NE(m.find("lacks FileStorage's first line '%YAML:1.0'"), std::string::npos) << m;
  m = errorOf([&] { readCalibrationFile(dir.file("absent.yaml")); });
  EXPECT_NE(m.find("absent.yaml': cannot be read"), std::string::npos) << m;
}

/// A FileStorage YAML with the given lines after the header.
std::string opencvYaml(const std::string& lines) { return "%YAML:1.0\n---\n" + lines; }
const std::string kKYaml =
    "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ 400., 0., 640., 0., 400., 480., 0., "
    "0., 1. ]\n";
const std::string kDYaml =
    "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 4\n   dt: d\n   data: [ 0., 0., 0., 0. ]\n";

TEST(CalibrationFiles, MalformedOpenCvFilesNameTheKey) {
  t::TempDir dir;
  const std::string path = dir.file("bad.yaml");
  struct Case {
    std::string text, expect;
  };
  const std::vector<Case> cases = {
      {opencvYaml(kKYaml + kDYaml + "xi: [1, 2\n"), "not a readable OpenCV FileStorage file"},
      {opencvYaml(kDYaml + "xi: 1.0\n"), "key 'camera_matrix' is missing"},
      {opencvYaml(kKYaml + "xi: 1.0\n"), "key 'distortion_coefficients' is missing"},
      {opencvYaml(kKYaml + kDYaml + "xi: -0.5\n"), "key 'xi' must be a number >= 0, found -0.5"},
      {opencvYaml(kKYaml + kDYaml + "xi: .nan\n"), "key 'xi' must be a number >= 0"},
      {opencvYaml(kKYaml + kDYaml + "xi: one\n"), "key 'xi'"},
      {opencvYaml(
           "camera_matrix: !!opencv-matrix\n   rows: 2\n   cols: 3\n   dt: d\n   data: [ 1., 0., 1., 0., 1., 1. ]\n" +
           kDYaml + "xi: 1.0\n"),
       "key 'camera_matrix' must be a 3x3 matrix, found 2x3"},
      {opencvYaml("camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ -4., 0., 6., 0., 4., "
                  "4., 0., 0., 1. ]\n" +
                  kDYaml + "xi: 1.0\n"),
       "key 'camera_matrix': fx and fy must be > 0, found -4, 4"},
      {opencvYaml("camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ 4., 0., 6., 1., 4., "
                  "4., 0., 0., 1. ]\n" +
                  kDYaml + "xi: 1.0\n"),
       "key 'camera_matrix' must be [fx s cx; 0 fy cy; 0 0 1]"},
      {opencvYaml(
           kKYaml +
           "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 3\n   dt: d\n   data: [ 0., 0., 0. ]\n" +
           "xi: 1.0\n"),
       "key 'distortion_coefficients' must be a 1x4 matrix (or its transpose), found 1x3"},
      {opencvYaml(kKYaml + "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: [ 0., "
                           "0., 0., 0., 0. ]\n"),
       "a pinhole calibration (cv::calibrateCamera)"},
      {opencvYaml(kKYaml + kDYaml + "xi: 1.0\nimage_width: 640\n"),
       "key 'image_height' must be an integer in [1, 16384]"},
      {opencvYaml(kKYaml + kDYaml + "xi: 1.0\nimage_width: 0\nimage_height: 480\n"),
       "key 'image_width' must be an integer"},
      {opencvYaml("rms: 0.4\n"), "key 'camera_matrix' is missing"},
      // Found by tests/fuzz (regressions/calibration): OpenCV allocated the declared 3 x 2^31 doubles
      // (48 GB) before reading the data; the declared shape is refused first.
      {opencvYaml("camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 2147483647\n   dt: d\n   data: [ 1. ]\n" +
                  kDYaml + "xi: 1.0\n"),
       "key 'camera_matrix' must be a 3x3 matrix, found 3x2147483647 (declared)"},
      // Found by tests/fuzz (regressions/calibration): the declared rows x cols of the distortion
      // overflowed int (UBSan) before its shape was checked.
      {opencvYaml(
           kKYaml +
           "distortion_coefficients: !!opencv-matrix\n   rows: 2147483647\n   cols: 4\n   dt: d\n   data: [ 0. ]\n" +
           "xi: 1.0\n"),
       "key 'distortion_coefficients' must be a 1x4 matrix (or its transpose), found 2147483647x4"},
      {opencvYaml(
           kKYaml +
           "distortion_coefficients: !!opencv-matrix\n   rows: 2147483647\n   cols: 4\n   dt: d\n   data: [ 0. ]\n"),
       "has 8589934588 values and there is no 'xi'"},
      // Found by tests/fuzz (regressions/calibration): a list at the top level made OpenCV's
      // FileNode::operator[] throw cv::Exception out of the reader.
      {opencvYaml("- 1\n- 2\n"), "not a readable OpenCV FileStorage file"},
      // Found by tests/fuzz (regressions/calibration, timeout-*): OpenCV 4.6's YAML parser never
      // returned on these; the YAML dialect is read by yaml-cpp now (src/opencv_storage.h).
      {"%YAML:1.\n -+\n,  -\nm", "not a readable OpenCV FileStorage file"},
      {"%YAML:1.\n a:]\ni:\n-", "not a readable OpenCV FileStorage file"},
      {opencvYaml(kKYaml + kDYaml + kDYaml + "xi: 1.0\n"), "not a readable OpenCV FileStorage file"},
      {opencvYaml(kKYaml + "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 4\n   dt: d\n   data: [ "
                           "0., 0., 0. ]\nxi: 1.0\n"),
       "key 'distortion_coefficients' is not an OpenCV matrix: its data must be a list of rows x cols x channels = 4"},
      {opencvYaml(kKYaml + "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 4\n   dt: d\n   data: [ "
                           "0., 0., a, 0. ]\nxi: 1.0\n"),
       "key 'distortion_coefficients' is not an OpenCV matrix: its data holds something that is not a number"},
      {opencvYaml(kKYaml + "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 4\n   dt: 2d\n   data: [ "
                           "0., 0., 0., 0., 0., 0., 0., 0. ]\nxi: 1.0\n"),
       "key 'distortion_coefficients' must be a 1x4 matrix (or its transpose), found 1x4 with 2 channels"},
      {opencvYaml(kKYaml + "distortion_coefficients: 0.5\nxi: 1.0\n"),
       "key 'distortion_coefficients' is a number, not an OpenCV matrix"},
      {opencvYaml(kKYaml + kDYaml + "xi: 1.0\nimage_width: 640.5\nimage_height: 480\n"),
       "key 'image_width' must be an integer"},
      // Found by tests/fuzz (regressions/calibration, crash-ceecaada...): OpenCV 4.6's XML parser
      // dereferenced a null pointer on these 8 bytes; the XML form is read by pugixml now.
      {"<?xml n=", "unknown calibration format"},
      {"<?xml version=\"1.0\"?>\n<opencv_storage>\n<xi>1.</x", "not a readable OpenCV FileStorage file: not valid XML"},
      {"<?xml version=\"1.0\"?>\n<opencv_storage>\n<xi>1.</xi><xi>2.</xi></opencv_storage>\n",
       "not a readable OpenCV FileStorage file: key 'xi' is given twice"},
      // The XML form: the declared shape is refused before anything is allocated for it.
      {"<?xml version=\"1.0\"?>\n<opencv_storage>\n<camera_matrix type_id=\"opencv-matrix\"><rows>3</rows>"
       "<cols>2147483647</cols><dt>d</dt><data>1.</data></camera_matrix>\n<xi>1.</xi>\n</opencv_storage>\n",
       "key 'camera_matrix' must be a 3x3 matrix, found 3x2147483647 (declared)"},
  };
  for (const Case& c : cases) {
    writeText(path, c.text);
    const std::string m = errorOf([&] { readCalibrationFile(path); });
    EXPECT_EQ(m.rfind("'" + path + "': ", 0), 0u) << m;
    EXPECT_NE(m.find(c.expect), std::string::npos) << c.text << "\n-> " << m;
  }
  // Explicit formats: an omnidir file needs xi; without it, it is a fisheye file.
  writeText(path, opencvYaml(kKYaml + kDYaml));
  EXPECT_NE(errorOf([&] {
              readCalibrationFile(path, {CalibrationFormat::kOpencvOmnidir, ""});
            }).find("is an OpenCV fisheye FileStorage file, not an OpenCV omnidir (Mei) FileStorage file"),
            std::string::npos);
  writeText(path, opencvYaml(kKYaml + "xi: 1.0\n"));
  EXPECT_NE(errorOf([&] {
              readCalibrationFile(path, {CalibrationFormat::kOpencvOmnidir, ""});
            }).find("key 'distortion_coefficients' is missing"),
            std::string::npos);
}

TEST(CalibrationFiles, MalformedKalibrFilesNameTheKeyAndLine) {
  t::TempDir dir;
  const std::string path = dir.file("camchain.yaml");
  const std::string ok_tail = "  intrinsics: [1.1, 458.6, 457.3, 367.2, 248.4]\n  resolution: [752, 480]\n";
  struct Case {
    std::string text, expect;
  };
  const std::vector<Case> cases = {
      {"cam0:\n  camera_model: pinhole\n  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0, 0]\n" + ok_tail,
       "key 'cam0.camera_model' (line 2) pinhole + radtan is not supported; supported (camera_model + "
       "distortion_model): omni + radtan, omni + none, pinhole + equidistant, ds + none, eucm + none"},
      {"cam0:\n  camera_model: omni\n  distortion_model: fov\n  distortion_coeffs: [0.9]\n" + ok_tail,
       "omni + fov is not supported"},
      {"cam0:\n  camera_model: omni\n  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0]\n" + ok_tail,
       "key 'cam0.distortion_coeffs' must be a list of 4 numbers in [-1e+12, 1e+12] (line 4)"},
      {"cam0:\n  camera_model: omni\n  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0, 0]\n"
       "  intrinsics: [458.6, 457.3, 367.2, 248.4]\n",
       "key 'cam0.intrinsics' must be a list of 5 numbers in [-1e+12, 1e+12] (line 5)"},
      {"cam0:\n  camera_model: omni\n  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0, 0]\n"
       "  intrinsics: [1.1, 0, 457.3, 367.2, 248.4]\n",
       "key 'cam0.intrinsics' (line 5) focal lengths fu, fv must be > 0"},
      {"cam0:\n  camera_model: omni\n  distortion_model: radtan\n  distortion_coeffs: [0, 0, 0, 0]\n"
       "  intrinsics: [-1.1, 458.6, 457.3, 367.2, 248.4]\n",
       "xi (item 0) must be >= 0"},
      {"cam0:\n  camera_model: ds\n  distortion_model: none\n  intrinsics: [0.1, 1.5, 350, 351, 640, 400]\n",
       "alpha (item 1) must be in [0, 1]"},
      {"cam0:\n  camera_model: eucm\n  distortion_model: none\n  intrinsics: [0.5, -1, 350, 351, 640, 400]\n",
       "beta (item 1) > 0"},
      {"cam0:\n  camera_model: omni\n  distortion_model: none\n  intrinsics: [1.1, 458.6, 457.3, 367.2, 248.4]\n"
       "  resolution: [752.5, 480]\n",
       "key 'cam0.resolution' (line 5) must be two whole numbers"},
      {"cam0:\n  distortion_model: none\n  intrinsics: [1.1, 458.6, 457.3, 367.2, 248.4]\n",
       "unknown calibration format"},  // no camera_model anywhere: not recognisable as Kalibr
      {"cam0:\n  camera_model: omni\n  intrinsics: [1, 2\n", "unknown calibration format"},
  };
  for (const Case& c : cases) {
    writeText(path, c.text);
    const std::string m = errorOf([&] { readCalibrationFile(path); });
    EXPECT_NE(m.find(path), std::string::npos) << m;
    EXPECT_NE(m.find(c.expect), std::string::npos) << c.text << "\n-> " << m;
  }
  // Given as Kalibr explicitly, broken YAML is named as such; a missing camera is named.
  writeText(path, "cam0:\n  camera_model: omni\n  intrinsics: [1, 2\n");
  EXPECT_NE(errorOf([&] {
              readCalibrationFile(path, {CalibrationFormat::kKalibr, ""});
            }).find("not valid YAML"),
            std::string::npos);
  writeText(path,
            "cam0:\n  camera_model: eucm\n  distortion_model: none\n  intrinsics: [0.5, 1, 350, 351, 640, 400]\n");
  EXPECT_NE(errorOf([&] {
              readCalibrationFile(path, {std::nullopt, "cam3"});
            }).find("has no camera 'cam3'"),
            std::string::npos);
}

TEST(CalibrationFiles, MalformedOcamCalibNamesTheLine) {
  t::TempDir dir;
  const std::string path = dir.file("calib_results.txt");
  std::string text = kOcamText;
  text.replace(text.find("480 748"), 7, "480 x");
  writeText(path, text);
  const std::string m = errorOf([&] { readCalibrationFile(path); });
  EXPECT_NE(m.find(path), std::string::npos) << m;
  EXPECT_NE(m.find("line"), std::string::npos) << m;
}

}  // namespace
