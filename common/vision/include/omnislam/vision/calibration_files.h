// Readers of the camera calibration files users already have (docs/user/calibration.md): OpenCV
// FileStorage YAML/XML from cv::omnidir (Mei) or cv::fisheye (Kannala-Brandt) calibration, Kalibr
// camchain.yaml, OCamCalib calib_results.txt; format detection by content; the camera model built
// from what was read.
//
// Why here (omnislam_vision) and not in the pure core or omnislam_config: OpenCV's XML is read by
// cv::FileStorage, so the reader needs OpenCV, which the core must not use and the config library
// (used by OpenCV-free processes such as omnislam-slam) does not link. OpenCV's YAML dialect
// ("%YAML:1.0", !!opencv-matrix) and Kalibr's plain YAML go through yaml-cpp and config::Node
// (src/opencv_storage.h says why not cv::FileStorage: OpenCV 4.6's YAML parser hangs on some files).
//
// What is read is kept in neutral structs (the file's own parameters, in its own units: pixels for
// focal lengths, centres and skew; dimensionless distortion, xi, alpha, beta); makeCalibratedCamera()
// is the one place that turns them into camera::CameraModel objects.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <variant>

#include "omnislam/core/camera/camera_model.h"
#include "omnislam/core/camera/scaramuzza.h"

namespace omnislam::vision {

enum class CalibrationFormat {
  kOpencvOmnidir,  ///< cv::FileStorage: camera_matrix, distortion_coefficients (k1 k2 p1 p2), xi
  kOpencvFisheye,  ///< cv::FileStorage: camera_matrix, distortion_coefficients (k1 k2 k3 k4), no xi
  kKalibr,         ///< Kalibr camchain.yaml: camN.{camera_model, intrinsics, distortion_*, resolution}
  kOcamcalib,      ///< OCamCalib calib_results.txt (camera::parseOcamCalib)
};

/// The config spelling: "opencv_omnidir", "opencv_fisheye", "kalibr", "ocamcalib".
std::string formatKey(CalibrationFormat f);
/// For messages, e.g. "an OpenCV omnidir (Mei) FileStorage file".
std::string formatDescription(CalibrationFormat f);

/// Mei unified model with radial-tangential distortion (cv::omnidir, Kalibr omni + radtan / none).
/// Pixel: u = fx_px x_d + skew_px y_d + cx_px, v = fy_px y_d + cy_px (OpenCV's K).
struct MeiIntrinsics {
  double fx_px = 0, fy_px = 0, cx_px = 0, cy_px = 0, skew_px = 0;
  double xi = 0;                          ///< mirror parameter, >= 0
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0;  ///< radial, tangential distortion
};
/// Kannala-Brandt equidistant model (cv::fisheye, Kalibr pinhole + equidistant):
/// theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8).
struct KannalaBrandtIntrinsics {
  double fx_px = 0, fy_px = 0, cx_px = 0, cy_px = 0, skew_px = 0;
  double k1 = 0, k2 = 0, k3 = 0, k4 = 0;
};
/// Double sphere (Usenko et al. 2018; Kalibr ds): intrinsics [xi alpha fu fv pu pv].
struct DoubleSphereIntrinsics {
  double fx_px = 0, fy_px = 0, cx_px = 0, cy_px = 0, xi = 0, alpha = 0;
};
/// Extended unified camera model (Khomutenko et al. 2016; Kalibr eucm): [alpha beta fu fv pu pv].
struct EucmIntrinsics {
  double fx_px = 0, fy_px = 0, cx_px = 0, cy_px = 0, alpha = 0, beta = 0;
};

using CalibratedIntrinsics = std::variant<MeiIntrinsics, KannalaBrandtIntrinsics, DoubleSphereIntrinsics,
                                          EucmIntrinsics, camera::ScaramuzzaParams>;

/// What a calibration file says about one camera.
struct CameraCalibration {
  CalibrationFormat format = CalibrationFormat::kOpencvOmnidir;
  CalibratedIntrinsics intrinsics;
  int width_px = 0;  ///< image size the file states [px]; 0 when it states none
  int height_px = 0;
  std::string description;  ///< one line for logs, e.g. "Kalibr cam0 (omni + radtan) of 'x.yaml'"
};

struct CalibrationReadOptions {
  std::optional<CalibrationFormat> format;  ///< nullopt: detect the format by content
  std::string kalibr_camera;                ///< Kalibr camera key ("cam1"); empty: the first in the file
};

/// The format of a calibration file's text, judged by content only (no parsing of the values):
/// "%YAML:1." or an <opencv_storage> XML root -> OpenCV (omnidir when it has a top-level xi, else
/// fisheye); a YAML map of maps with camera_model -> Kalibr; text that parseOcamCalib accepts ->
/// OCamCalib. nullopt when none fits.
std::optional<CalibrationFormat> detectCalibrationFormat(const std::string& text);

/// Parses a calibration file's text; `source` names it in messages. Throws config::ConfigError with
/// one line naming the source, the key or line and what is wrong; for a format other than the one
/// requested, the message names the format found; for an unknown format, the formats accepted.
CameraCalibration parseCalibration(const std::string& text, const std::string& source,
                                   const CalibrationReadOptions& options = {});

/// Reads and parses a file (parseCalibration); throws config::ConfigError if it cannot be read.
CameraCalibration readCalibrationFile(const std::string& path, const CalibrationReadOptions& options = {});

/// The camera model of a calibration, for an image of width_px x height_px: MeiCamera,
/// KannalaBrandtCamera, DoubleSphereCamera or EucmCamera, wrapped in ReflectedCamera when `optics`
/// is kCatadioptric (camera looking up into a mirror: d_C = diag(1, 1, -1) d_calibration); an
/// OCamCalib calibration becomes a ScaramuzzaCamera with params.optics = optics. Throws
/// config::ConfigError naming the calibration when the model refuses the parameters (validate()).
std::unique_ptr<camera::CameraModel> makeCalibratedCamera(const CameraCalibration& calibration,
                                                          camera::OcamOptics optics, int width_px, int height_px);

/// The pixel of the calibration's optical axis, (cx, cy) [px] ((yc, xc) for OCamCalib).
Eigen::Vector2d principalPointPx(const CameraCalibration& calibration);

}  // namespace omnislam::vision
