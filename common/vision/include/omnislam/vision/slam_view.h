// The SLAM view that omnislam-viewer shows live and writes headless to PNG: a top-down map panel
// (map frame W: x right, y up, metres, equal axis scales) beside the current omnidirectional
// image with its features and their associations. Plain structs in, a BGR 8-bit cv::Mat out, so
// that the drawing is testable without a bus or a display.
//
// Map panel: estimated landmarks with their 2-sigma x-y covariance ellipse, coloured by type
// (type I red, type II orange, paper 000 III-F), true landmarks (black circles), particles (small
// violet dots), true trajectory (grey), estimated trajectory (blue), current estimate (blue arrow
// with its 2-sigma x-y ellipse) and true pose (grey arrow), the global localiser's hypotheses while it
// searches (teal arrows with their 2-sigma x-y ellipses, numbered best first, the best one thicker),
// a metre grid with labels, a scale bar.
// Image panel: the image (grey or BGR) scaled to the panel; each feature a circle at its (u, v)
// pixel, green with the landmark id when associated, orange when it went to the candidates
// (associations_t NOT_ASSOCIATED), grey when not used (NOT_USED), cyan when no association is
// known for the frame.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/core/pose2.h"

namespace omnislam::vision {

struct ViewLandmark {
  int64_t id = 0;
  Eigen::Vector3d p_m = Eigen::Vector3d::Zero();        ///< position in W, metres
  Eigen::Matrix2d cov_xy_m2 = Eigen::Matrix2d::Zero();  ///< x-y block of the covariance, m^2
  int type = 0;                                         ///< 1 (type I, reliable), 2 (type II), 0 unknown
  int kind = 1;  ///< feature_t KIND_*: 1 ceiling light (cross), 2 vertical line (diamond)
};

struct ViewParticle {
  Pose2 pose;
  double weight = 0.0;
};

/// One hypothesis of the global localiser (SLAM_LOCALISATION): the pose of R in W.
struct ViewHypothesis {
  Pose2 pose;
  Eigen::Matrix2d cov_xy_m2 = Eigen::Matrix2d::Zero();  ///< x-y block of its covariance, m^2
  double relative_log_likelihood = 0.0;                 ///< 0 for the best, < 0 for the others
};

/// Association codes of a feature (the non-negative values are landmark ids).
inline constexpr int64_t kAssocNotUsed = -1;        ///< = associations_t::NOT_USED
inline constexpr int64_t kAssocNotAssociated = -2;  ///< = associations_t::NOT_ASSOCIATED
inline constexpr int64_t kAssocUnknown = -100;      ///< no association message for the frame

struct ViewFeature {
  double u_px = 0.0;  ///< column in the image, pixels
  double v_px = 0.0;  ///< row in the image, pixels
  int kind = 1;
  int64_t landmark_id = kAssocUnknown;  ///< landmark id, or one of the kAssoc* codes
};

/// Everything one view shows. Any part may be empty: the panel then says so.
struct SlamViewData {
  std::string title;                  ///< top line of the map panel
  std::vector<std::string> info;      ///< status lines under the title (time, counts, ...)
  std::vector<Pose2> estimate_track;  ///< estimated trajectory, oldest first
  std::vector<Pose2> truth_track;     ///< true trajectory, oldest first
  std::optional<Pose2> pose;          ///< current estimate
  Eigen::Matrix2d pose_cov_xy_m2 = Eigen::Matrix2d::Zero();
  std::optional<Pose2> true_pose;  ///< true pose at the estimate's time
  std::vector<ViewLandmark> landmarks;
  std::vector<Eigen::Vector3d> true_landmarks;
  std::vector<ViewParticle> particles;
  std::vector<ViewHypothesis> hypotheses;  ///< the global localiser's, best first (while it searches)
  cv::Mat image;                           ///< CV_8UC1 or CV_8UC3; empty when there is none
  std::string image_caption;               ///< line under the image (time, counts)
  std::vector<ViewFeature> features;       ///< features of `image`
};

struct SlamViewOptions {
  int map_width_px = 820;    ///< map panel width
  int height_px = 720;       ///< height of the whole view (both panels)
  int image_width_px = 720;  ///< image panel width; 0 = no image panel
  double margin_m = 1.0;     ///< free border around the content of the map, metres
  /// The map's extent is fitted to landmarks, true landmarks, trajectories and poses; particles
  /// only count if they are within this distance of the estimate (a stray particle must not
  /// shrink everything), metres.
  double particle_extent_m = 5.0;
  double arrow_length_px = 22.0;  ///< length of the heading arrows
  bool landmark_ids = true;       ///< write each estimated landmark's id beside it
};

/// World (W, metres) to map-panel pixels: equal scales, y up.
struct MapTransform {
  double scale_px_per_m = 1.0;
  double cx_m = 0.0, cy_m = 0.0;  ///< world point at the centre of the plot area
  cv::Point2d centre_px;          ///< its pixel in the view
  cv::Point2d toPixel(double x_m, double y_m) const {
    return {centre_px.x + (x_m - cx_m) * scale_px_per_m, centre_px.y - (y_m - cy_m) * scale_px_per_m};
  }
};

/// Where things go in the view (both panels in one image).
struct SlamViewLayout {
  cv::Size size;           ///< the whole view
  cv::Rect map_rect;       ///< the map panel
  cv::Rect plot_rect;      ///< the plot area inside the map panel
  MapTransform map;        ///< world -> view pixel
  cv::Rect image_rect;     ///< the image panel (empty if none)
  cv::Rect image_draw;     ///< where the scaled image is drawn (empty if no image)
  double image_scale = 1;  ///< view pixels per image pixel
  /// Image pixel (u, v) -> view pixel.
  cv::Point2d imageToView(double u_px, double v_px) const {
    return {image_draw.x + (u_px + 0.5) * image_scale - 0.5, image_draw.y + (v_px + 0.5) * image_scale - 0.5};
  }
};

SlamViewLayout layoutSlamView(const SlamViewData& data, const SlamViewOptions& opt = {});
/// The whole view (BGR, 8-bit), of layoutSlamView(data, opt).size.
cv::Mat renderSlamView(const SlamViewData& data, const SlamViewOptions& opt = {});

/// Colours (BGR) of the legend, for tests and docs.
namespace view_colours {
inline const cv::Scalar kLandmarkType1(30, 30, 220);   // red
inline const cv::Scalar kLandmarkType2(0, 150, 255);   // orange
inline const cv::Scalar kLandmarkOther(160, 60, 160);  // purple (type unknown)
inline const cv::Scalar kTrueLandmark(0, 0, 0);        // black
inline const cv::Scalar kEstimate(200, 90, 20);        // blue
inline const cv::Scalar kTruth(150, 150, 150);         // grey
inline const cv::Scalar kParticle(200, 60, 200);       // violet
inline const cv::Scalar kHypothesis(140, 140, 0);      // teal
inline const cv::Scalar kFeatAssociated(40, 220, 40);  // green
inline const cv::Scalar kFeatCandidate(0, 165, 255);   // orange
inline const cv::Scalar kFeatNotUsed(170, 170, 170);   // grey
inline const cv::Scalar kFeatUnknown(255, 255, 0);     // cyan
}  // namespace view_colours

/// A trajectory kept within a bounded number of points: a pose is appended only if it moved at
/// least min_step_m (or turned min_turn_rad) from the last kept one; when the track reaches
/// max_points, every other point is dropped and the steps double. The latest pose is always the
/// last point (it replaces an unkept tail), so the drawn track ends at the current pose.
class TrackBuffer {
 public:
  explicit TrackBuffer(size_t max_points = 20000, double min_step_m = 0.02, double min_turn_rad = 0.05);
  void add(const Pose2& p);
  void clear();
  const std::vector<Pose2>& points() const { return pts_; }

 private:
  size_t max_points_;
  double min_step_m_, min_turn_rad_;
  std::vector<Pose2> pts_;
  bool tail_is_temporary_ = false;  ///< the last point is the latest pose, not a kept one
};

}  // namespace omnislam::vision
