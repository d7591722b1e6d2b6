// omnislam-calibrate's steps (docs/user/calibration.md): checkerboard corners in each image, intrinsic
// calibration with cv::omnidir (Mei unified model) or cv::fisheye (Kannala-Brandt), per-view
// reprojection errors, the FileStorage YAML that `camera.model: auto` reads, annotated views.
//
// Units: pixels for image points and errors ((0, 0) = centre of the top-left pixel, OpenCV's
// convention), metres for the board. The board frame: x along the corner columns, y along the rows,
// z = 0 on the board; inner corner (i, j) (column i, row j) at (i, j, 0) * square_m.
#pragma once

#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

namespace omnislam::calib {

/// The checkerboard: its INNER corners (where four squares meet), columns x rows, and the side of
/// one square [m].
struct BoardSpec {
  cv::Size inner_corners{0, 0};  ///< width = corners per row, height = corners per column; each >= 2
  double square_m = 0.0;         ///< > 0
};

enum class LensModel { kOmnidir, kFisheye };

/// The corners found in one image, in the board's row-major order.
struct BoardView {
  std::string file;                  ///< file name (no folder)
  std::vector<cv::Point2d> corners;  ///< [px]
  const char* detector = "";         ///< "classic" (findChessboardCorners + cornerSubPix) or "sb"
};

/// Corners of the board in an 8-bit grey image: cv::findChessboardCorners refined by cornerSubPix
/// (window: 0.3 x the smallest distance between neighbouring corners, so it never reaches the next
/// corner, clamped to 2..10 px half-size), else cv::findChessboardCornersSB (sub-pixel itself).
/// nullopt when neither finds the whole board.
std::optional<BoardView> detectBoard(const cv::Mat& grey, const BoardSpec& board);

/// One view's calibration outcome.
struct ViewResult {
  bool used = false;                     ///< false: cv::omnidir dropped it at initialisation
  double rms_px = 0.0;                   ///< sqrt(mean |corner - reprojection|^2)
  std::vector<cv::Point2d> reprojected;  ///< [px], the board's corners through the calibrated model
  cv::Vec3d rvec, tvec;                  ///< board pose in the camera frame (Rodrigues [rad], [m])
};

struct Calibration {
  LensModel model = LensModel::kOmnidir;
  cv::Size image_size;
  cv::Matx33d K;                  ///< [fx s cx; 0 fy cy; 0 0 1] [px]
  cv::Vec4d D;                    ///< omnidir: k1 k2 p1 p2; fisheye: k1 k2 k3 k4
  double xi = 0.0;                ///< omnidir only
  int flags = 0;                  ///< the OpenCV calibration flags used
  double rms_px = 0;              ///< over every corner of the used views, sqrt(mean |e|^2)
  std::vector<ViewResult> views;  ///< one per input view, in order
};

/// Calibrates from the views (all of the same board); throws std::invalid_argument with the
/// solver's message when OpenCV fails, or when fewer than 3 views survive.
Calibration calibrate(const std::vector<BoardView>& views, const BoardSpec& board, cv::Size image_size,
                      LensModel model);

/// Writes the FileStorage YAML: `comment` lines (each prefixed "# "), then the omnidir sample's keys
/// (calibration_time, nFrames, flags, camera_matrix, distortion_coefficients, xi for omnidir,
/// used_imgs, extrinsic_parameters, rms) and image_width, image_height. Throws
/// std::invalid_argument when the file cannot be written.
void writeCalibration(const std::string& path, const Calibration& c, const std::vector<BoardView>& views,
                      const std::vector<std::string>& comment);

/// The image with the detected corners (cv::drawChessboardCorners) and their reprojections (red crosses) and the view's
/// rms; `view`/`result` null: marked "board not found".
cv::Mat annotateView(const cv::Mat& image, const BoardView* view, const ViewResult* result, const BoardSpec& board);

}  // namespace omnislam::calib
