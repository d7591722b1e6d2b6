// image_t <-> cv::Mat: see image_msg.h.
#include "omnislam/lcmio/image_msg.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <stdexcept>

namespace omnislam::lcmio {

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

std::optional<cv::Mat> decodeImage(const image_t& msg, std::string* why) {
  auto fail = [&](const std::string& w) -> std::optional<cv::Mat> {
    if (why) *why = w;
    return std::nullopt;
  };
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
      cv::Mat img = cv::imdecode(msg.data, cv::IMREAD_UNCHANGED);
      if (img.empty()) return fail("compressed image does not decode");
      if (img.cols != msg.width || img.rows != msg.height)
        return fail("decoded size " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                    " differs from the header's " + std::to_string(msg.width) + "x" + std::to_string(msg.height));
      if (img.depth() != CV_8U) return fail("compressed image is not 8-bit");
      return img;
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
