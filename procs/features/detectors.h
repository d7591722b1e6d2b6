// The detectors of omnislam-features behind one interface, built from the config file
// (docs/design/detectors.md). The config is validated when it is loaded: errors name the key.
#pragma once

#include <opencv2/core.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/config/yaml_node.h"
#include "omnislam/core/camera/camera_model.h"
#include "omnislam/core/camera/mounting.h"
#include "omnislam/feature_t.hpp"
#include "omnislam/vision/ceiling_lights.h"
#include "omnislam/vision/vertical_lines.h"

namespace omnislam::features {

class Detector {
 public:
  virtual ~Detector() = default;
  /// "ceiling_lights" or "vertical_lines" (features_t.detector).
  virtual std::string name() const = 0;
  /// Why the image cannot be processed (size, format), or nothing when it can.
  virtual std::optional<std::string> check(const cv::Mat& image) const = 0;
  /// Features of a checked image, at most max_features (the strongest).
  virtual std::vector<feature_t> detect(const cv::Mat& image) const = 0;
  /// The image with the features of the last detect() call on it drawn (for review).
  virtual cv::Mat annotate(const cv::Mat& image, const std::vector<feature_t>& features) const = 0;
  /// Position of the optical centre in the robot frame [m].
  virtual camera::CameraMounting mounting() const = 0;
  /// One line describing the detector and its camera, for the log.
  virtual std::string describe() const = 0;
  /// Every key of its config section as used, "key=value ..." (the start-up echo,
  /// detector_options_table.h).
  virtual std::string options() const = 0;
};

/// Builds the detector a features config file describes; throws config::ConfigError naming the
/// key on any invalid or unknown setting.
std::unique_ptr<Detector> makeDetector(const config::Node& root);

/// The vertical-line detector options of a features config file (its camera and vertical_lines
/// sections), validated exactly as makeDetector() does; for tools and tests that run the
/// library detector directly.
vision::VerticalLineOptions verticalLineOptions(const config::Node& root);

/// The camera and ceiling-light options of a features config file (its camera and ceiling_lights
/// sections), validated exactly as makeDetector() does; for tools and tests that run the library
/// detector directly (vision::CeilingLightDetector keeps a reference to `camera`).
struct CeilingLightSetup {
  std::unique_ptr<camera::CameraModel> camera;
  camera::CameraMounting mounting;
  vision::CeilingLightOptions options;
};
CeilingLightSetup ceilingLightSetup(const config::Node& root);

/// The camera's mask of a features config file (camera.mask, camera.mask_annulus; CV_8UC1, 255 =
/// use), loaded and validated exactly as makeDetector() does; empty when the file has none.
cv::Mat cameraMask(const config::Node& root);

}  // namespace omnislam::features
