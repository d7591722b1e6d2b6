// Fuzz entry points of images and cameras: the header checks and the decode of every accepted image
// format (common/vision image_header.cpp, image_decode.cpp) and the calibration file readers (OpenCV
// omnidir and fisheye FileStorage, Kalibr camchain, OCamCalib text; calibration_files.cpp,
// scaramuzza.cpp) with the camera model they make, as a features config's `camera.model: auto` does.
#include <Eigen/Core>
#include <opencv2/imgcodecs.hpp>

#include <string>

#include "entry_points.h"
#include "guard.h"
#include "omnislam/core/camera/scaramuzza.h"
#include "omnislam/config/yaml_node.h"
#include "omnislam/vision/calibration_files.h"
#include "omnislam/vision/image_decode.h"
#include "omnislam/vision/image_header.h"

namespace omnislam::fuzz {
namespace {

/// A decoded image must be what its header announced (decodeInspected's promise).
void checkDecoded(const vision::DecodedImage& d, const char* target) {
  if (!d.ok()) return;
  if (!d.header || d.image.empty()) reportUnexpected(target, "accepted", "an image without header or pixels");
  if (d.image.cols != d.header->width_px || d.image.rows != d.header->height_px)
    reportUnexpected(target, "accepted",
                     "decoded " + std::to_string(d.image.cols) + "x" + std::to_string(d.image.rows) + " from " +
                         d.header->describe());
}

/// A few rays through the camera, as the detectors use it: none may crash or give a non-unit ray.
void exerciseCamera(const camera::CameraModel& cam, const char* target) {
  for (const Eigen::Vector2d& px : {Eigen::Vector2d(0.5 * cam.widthPx(), 0.5 * cam.heightPx()),
                                    Eigen::Vector2d(1.0, 1.0), Eigen::Vector2d(cam.widthPx() - 1.0, 2.0)}) {
    const auto d = cam.unproject(px);
    if (!d) continue;
    if (!(std::abs(d->norm() - 1.0) < 1e-6)) reportUnexpected(target, "camera", "unproject gave a non-unit ray");
    (void)cam.project(*d);
  }
}

}  // namespace

void fuzzImageHeader(const uint8_t* data, size_t size) {
  guard<>("image_header", [&] {
    const vision::HeaderResult h = vision::readImageHeader(data, size);
    if (h.header) (void)vision::checkComplete(*h.header, data, size);
  });
}

void fuzzImageDecode(const uint8_t* data, size_t size) {
  guard<>("image_decode", [&] {
    vision::DecodeOptions opt;  // the contract's limits, as omnislam-capture --source dir and logstat
    checkDecoded(vision::decodeImageBytes(data, size, opt), "image_decode");
    opt.flags = cv::IMREAD_GRAYSCALE;  // as omnislam-features --images
    checkDecoded(vision::decodeImageBytes(data, size, opt), "image_decode");
  });
}

void fuzzCalibration(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  guard<config::ConfigError>("calibration", [&] {
    const vision::CameraCalibration c = vision::parseCalibration(text, "fuzz.yaml");
    const auto cam = vision::makeCalibratedCamera(c, camera::OcamOptics::kDioptric, 640, 480);
    exerciseCamera(*cam, "calibration");
  });
}

void fuzzOcamCalib(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  guard<std::invalid_argument>("ocamcalib", [&] {
    const camera::OcamCalibParseResult r = camera::parseOcamCalib(text);
    if (!r.params) return;
    if (camera::ScaramuzzaCamera::validate(*r.params)) return;
    const camera::ScaramuzzaCamera cam(*r.params);
    exerciseCamera(cam, "ocamcalib");
  });
}

}  // namespace omnislam::fuzz
