// Conversion between OMNI_IMAGE messages and OpenCV images.
#pragma once

#include <opencv2/core.hpp>

#include <optional>
#include <string>

#include "omnislam/image_t.hpp"
#include "omnislam/vision/image_decode.h"

namespace omnislam::lcmio {

/// Fills msg's format, size and bytes from a CV_8UC1 (grey) or CV_8UC3 (BGR) image, encoding to
/// `format` (image_t::FORMAT_*). Throws std::invalid_argument for an unsupported combination.
void encodeImage(const cv::Mat& img, int8_t format, image_t& msg);

/// Decodes a (validated) message into a grey or BGR image; nothing plus `why` (one line) if it is
/// refused. A JPEG or PNG is refused from its header, before any pixel is allocated, when the header
/// is unreadable, beyond the contract's limits (sides 8192 px, 64 MiB decoded), not the message's
/// width x height or pixel_format, deeper than 8 bits, or fails `check` (a consumer's own, e.g. its
/// camera's size: vision::HeaderProbe); and when its data is truncated (no JPEG EOI, no PNG IEND).
std::optional<cv::Mat> decodeImage(const image_t& msg, std::string* why = nullptr,
                                   const vision::HeaderCheck& check = nullptr);

/// Parses "gray", "bgr", "rgb", "jpeg", "png" into image_t::FORMAT_*; nothing if unknown.
std::optional<int8_t> parsePixelFormat(const std::string& name);

}  // namespace omnislam::lcmio
