// Conversion between OMNI_IMAGE messages and OpenCV images.
#pragma once

#include <opencv2/core.hpp>

#include <optional>
#include <string>

#include "omnislam/image_t.hpp"

namespace omnislam::lcmio {

/// Fills msg's format, size and bytes from a CV_8UC1 (grey) or CV_8UC3 (BGR) image, encoding to
/// `format` (image_t::FORMAT_*). Throws std::invalid_argument for an unsupported combination.
void encodeImage(const cv::Mat& img, int8_t format, image_t& msg);

/// Decodes a (validated) message into a grey or BGR image; nothing plus `why` if it is corrupt.
std::optional<cv::Mat> decodeImage(const image_t& msg, std::string* why = nullptr);

/// Parses "gray", "bgr", "rgb", "jpeg", "png" into image_t::FORMAT_*; nothing if unknown.
std::optional<int8_t> parsePixelFormat(const std::string& name);

}  // namespace omnislam::lcmio
