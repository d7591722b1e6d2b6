// image_t <-> cv::Mat: see image_msg.h.
#include "omnislam/lcmio/image_msg.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "omnislam/lcmio/validate.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace omnislam::lcmio {

namespace {

/// The decoding limits of a receiver: the contract's (validate.h). A compressed frame may not
/// decode into more bytes than the same frame could carry uncompressed.
vision::ImageLimits receiverLimits() {
  const Limits contract;
  vision::ImageLimits lim;
  lim.max_side_px = contract.max_image_side_px;
  lim.max_pixels = lim.max_side_px * lim.max_side_px;
  lim.max_decoded_bytes = contract.max_image_bytes;
  lim.max_encoded_bytes = contract.max_image_bytes;
  return lim;
}

/// What every receiver requires of a compressed frame's header before decoding: the codec its
/// pixel_format names, the message's own width and height, 8 bits per channel.
std::optional<std::string> checkAgainstMessage(const vision::ImageHeader& h, const image_t& msg) {
  const auto codec = msg.pixel_format == image_t::FORMAT_PNG ? vision::ImageCodec::kPng : vision::ImageCodec::kJpeg;
  if (h.codec != codec)
    return std::string("pixel_format says ") + vision::codecName(codec) + ", the data is a " +
           vision::codecName(h.codec);
  if (h.width_px != msg.width || h.height_px != msg.height)
    return "compressed image's own header says " + std::to_string(h.width_px) + "x" + std::to_string(h.height_px) +
           ", the message's " + std::to_string(msg.width) + "x" + std::to_string(msg.height);
  if (h.bit_depth > 8) return h.describe() + ": OMNI_IMAGE carries 8-bit images";
  return std::nullopt;
}

}  // namespace

void encodeImage(const cv::Mat& img, int8_t format, image_t& msg) {
  if (img.depth() != CV_8U || (img.channels() != 1 && img.channels() != 3))
    throw std::invalid_argument("encodeImage: only 8-bit grey or BGR images are supported");
  msg.width = img.cols;
  msg.height = img.rows;
  msg.pixel_format = format;
  cv::Mat src;  // never aliases img: cvtColor into a header sharing img's data would overwrite the input
  switch (format) {
    case image_t::FORMAT_GRAY8:
      if (img.channels() == 3) cv::cvtColor(img, src, cv::COLOR_BGR2GRAY);
      else src = img;
      break;
    case image_t::FORMAT_BGR8:
      if (img.channels() == 1) cv::cvtColor(img, src, cv::COLOR_GRAY2BGR);
      else src = img;
      break;
    case image_t::FORMAT_RGB8:
      cv::cvtColor(img, src, img.channels() == 1 ? cv::COLOR_GRAY2RGB : cv::COLOR_BGR2RGB);
      break;
    case image_t::FORMAT_JPEG:
    case image_t::FORMAT_PNG: {
      std::vector<uint8_t> buf;
      cv::imencode(format == image_t::FORMAT_JPEG ? ".jpg" : ".png", img, buf);
      msg.row_stride = 0;
      msg.data = std::move(buf);
      msg.size = static_cast<int32_t>(msg.data.size());
      return;
    }
    default: throw std::invalid_argument("encodeImage: unknown pixel format " + std::to_string(format));
  }
  if (!src.isContinuous()) src = src.clone();
  msg.row_stride = static_cast<int32_t>(src.step[0]);
  msg.data.assign(src.data, src.data + src.total() * src.elemSize());
  msg.size = static_cast<int32_t>(msg.data.size());
}

std::optional<cv::Mat> decodeImage(const image_t& msg, std::string* why, const vision::HeaderCheck& check) {
  auto fail = [&](const std::string& w) -> std::optional<cv::Mat> {
    if (why) *why = w;
    return std::nullopt;
  };
  // Raw rows are wrapped, not copied, before the clone: their sizes must hold (validate checks the
  // same; a caller that skipped it must not read past the buffer).
  const bool raw = msg.pixel_format == image_t::FORMAT_GRAY8 || msg.pixel_format == image_t::FORMAT_BGR8 ||
                   msg.pixel_format == image_t::FORMAT_RGB8;
  if (raw) {
    const int64_t channels = msg.pixel_format == image_t::FORMAT_GRAY8 ? 1 : 3;
    const int64_t row_bytes = static_cast<int64_t>(msg.width) * channels;
    if (msg.width <= 0 || msg.height <= 0 || msg.row_stride < row_bytes ||
        static_cast<int64_t>(msg.data.size()) < static_cast<int64_t>(msg.row_stride) * (msg.height - 1) + row_bytes)
      return fail("raw image sizes (" + std::to_string(msg.width) + "x" + std::to_string(msg.height) + ", stride " +
                  std::to_string(msg.row_stride) + ") do not fit its " + std::to_string(msg.data.size()) + " bytes");
  }
  switch (msg.pixel_format) {
    case image_t::FORMAT_GRAY8:
      return cv::Mat(msg.height, msg.width, CV_8UC1, const_cast<uint8_t*>(msg.data.data()), msg.row_stride).clone();
    case image_t::FORMAT_BGR8:
      return cv::Mat(msg.height, msg.width, CV_8UC3, const_cast<uint8_t*>(msg.data.data()), msg.row_stride).clone();
    case image_t::FORMAT_RGB8: {
      cv::Mat rgb(msg.height, msg.width, CV_8UC3, const_cast<uint8_t*>(msg.data.data()), msg.row_stride);
      cv::Mat bgr;
      cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
      return bgr;
    }
    case image_t::FORMAT_JPEG:
    case image_t::FORMAT_PNG: {
      // Header first: limits, the message's own size, the caller's check, complete data; only then
      // are pixels allocated.
      const vision::HeaderCheck both = [&](const vision::ImageHeader& h) {
        if (auto bad = checkAgainstMessage(h, msg)) return bad;
        return check ? check(h) : std::nullopt;
      };
      vision::DecodeOptions opt;
      opt.limits = receiverLimits();
      opt.check = both;
      auto decoded = vision::decodeImageBytes(msg.data.data(), msg.data.size(), opt);
      if (!decoded.ok()) return fail(decoded.error);
      return decoded.image;
    }
    default: return fail("unknown pixel format");
  }
}

std::optional<int8_t> parsePixelFormat(const std::string& n) {
  if (n == "gray" || n == "grey") return image_t::FORMAT_GRAY8;
  if (n == "rgb") return image_t::FORMAT_RGB8;
  if (n == "bgr") return image_t::FORMAT_BGR8;
  if (n == "jpeg" || n == "jpg") return image_t::FORMAT_JPEG;
  if (n == "png") return image_t::FORMAT_PNG;
  return std::nullopt;
}

}  // namespace omnislam::lcmio
