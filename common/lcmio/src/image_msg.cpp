// image_t <-> cv::Mat: see image_msg.h.
#include "omnislam/lcmio/image_msg.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace omnislam::lcmio {

namespace {

uint32_t bigEndian(const std::vector<uint8_t>& d, size_t at, int bytes) {
  uint32_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | d[at + static_cast<size_t>(i)];
  return v;
}

/// Width and height written in a PNG's IHDR or a JPEG's first SOF segment; nothing if the bytes do
/// not hold one. Read before decoding, so that a header claiming a huge image is refused instead of
/// making OpenCV allocate it or throw (CV_IO_MAX_IMAGE_PIXELS).
std::optional<std::pair<uint32_t, uint32_t>> compressedImageSize(const std::vector<uint8_t>& d, int8_t format) {
  if (format == image_t::FORMAT_PNG) {
    static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (d.size() < 24 || !std::equal(kSignature, kSignature + 8, d.begin())) return std::nullopt;
    if (d[12] != 'I' || d[13] != 'H' || d[14] != 'D' || d[15] != 'R') return std::nullopt;
    return std::make_pair(bigEndian(d, 16, 4), bigEndian(d, 20, 4));
  }
  // JPEG: SOI, then segments (0xFF, marker, 2-byte length including itself) up to a SOFn.
  if (d.size() < 4 || d[0] != 0xFF || d[1] != 0xD8) return std::nullopt;
  size_t i = 2;
  while (i + 4 <= d.size()) {
    if (d[i] != 0xFF) return std::nullopt;
    const uint8_t marker = d[i + 1];
    if (marker == 0xFF) {  // fill byte
      ++i;
      continue;
    }
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {  // no length
      i += 2;
      continue;
    }
    const uint32_t len = bigEndian(d, i + 2, 2);
    const bool sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (sof) {
      if (len < 7 || i + 9 > d.size()) return std::nullopt;
      return std::make_pair(bigEndian(d, i + 7, 2), bigEndian(d, i + 5, 2));  // height first in SOF
    }
    if (marker == 0xDA || len < 2) return std::nullopt;  // scan data before any frame header
    i += 2 + len;
  }
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

std::optional<cv::Mat> decodeImage(const image_t& msg, std::string* why) {
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
        static_cast<int64_t>(msg.data.size()) <
            static_cast<int64_t>(msg.row_stride) * (msg.height - 1) + row_bytes)
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
      const auto header = compressedImageSize(msg.data, msg.pixel_format);
      if (!header) return fail("compressed image has no readable size in its header");
      if (header->first != static_cast<uint32_t>(msg.width) || header->second != static_cast<uint32_t>(msg.height))
        return fail("compressed image's own header says " + std::to_string(header->first) + "x" +
                    std::to_string(header->second) + ", the message's " + std::to_string(msg.width) + "x" +
                    std::to_string(msg.height));
      cv::Mat img;
      try {
        img = cv::imdecode(msg.data, cv::IMREAD_UNCHANGED);
      } catch (const cv::Exception& e) {  // never let a bad image escape into an LCM callback
        return fail(std::string("compressed image does not decode: ") + e.what());
      }
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
