// Headless plots of a SLAM run for people: the map and trajectories seen from above (like paper
// 000's fig. 6a) and the position / heading error over time (fig. 6b), rendered to images with
// OpenCV so that they can be written as PNG without a display.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <string>
#include <vector>

#include "omnislam/core/pose2.h"

namespace omnislam::vision {

struct PlotLandmark {
  Eigen::Vector3d p_m = Eigen::Vector3d::Zero();
  Eigen::Matrix2d cov_xy_m2 = Eigen::Matrix2d::Zero();  ///< drawn as a 2-sigma ellipse when non-zero
};

struct MapPlot {
  std::string title;
  std::vector<Pose2> estimate;                    ///< estimated trajectory (blue)
  std::vector<Pose2> truth;                       ///< true trajectory (grey)
  std::vector<PlotLandmark> estimated_landmarks;  ///< red crosses and ellipses
  std::vector<Eigen::Vector3d> true_landmarks;    ///< black circles
};

struct ErrorPlot {
  std::string title;
  std::vector<double> t_s;              ///< time of each sample, seconds from the start
  std::vector<double> position_err_m;   ///< top panel
  std::vector<double> heading_err_rad;  ///< bottom panel (absolute value plotted)
};

/// A top view with equal axis scales, a metre grid and a legend (BGR, 8-bit).
cv::Mat renderMapPlot(const MapPlot& plot, int width_px = 1000, int height_px = 700);
/// Two panels sharing the time axis (BGR, 8-bit).
cv::Mat renderErrorPlot(const ErrorPlot& plot, int width_px = 1000, int height_px = 520);

}  // namespace omnislam::vision
