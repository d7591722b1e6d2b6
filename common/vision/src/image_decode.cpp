// Checked decoding of encoded images: see image_decode.h.
#include "omnislam/vision/image_decode.h"

#include <opencv2/imgproc.hpp>

#include <csetjmp>
#include <cstdint>
#include <cstdio>  // before jpeglib.h, which uses FILE
#include <fstream>
#include <stdexcept>
#include <system_error>

#include <jpeglib.h>
#include <jerror.h>  // after jpeglib.h

namespace omnislam::vision {
namespace {

// ---------------------------------------------------------------- JPEG through libjpeg
// OpenCV's JPEG decoder prints libjpeg's warnings on stderr and returns the image: a frame whose
// entropy-coded data is damaged comes back with invented blocks. Decoding with libjpeg itself (the
// library OpenCV's decoder uses, with the same settings) lets the warnings that mean lost or
// invented pixels refuse the frame.

struct JpegErrors {
  jpeg_error_mgr mgr;  // first: libjpeg hands back a pointer to it
  std::jmp_buf jump;
  std::string message;  ///< the fatal error, or the first warning that refuses the image
  int refusing_warnings = 0;
};

/// Warnings of damaged data: pixels lost or invented. Others (extraneous bytes between segments, a
/// camera's non-standard SOS or ICC marker) leave the pixels as coded and are not reasons to refuse.
bool meansDamagedData(int code) {
  return code == JWRN_HIT_MARKER || code == JWRN_HUFF_BAD_CODE || code == JWRN_JPEG_EOF || code == JWRN_MUST_RESYNC ||
         code == JWRN_BOGUS_PROGRESSION;
}

std::string formatted(j_common_ptr c) {
  char buf[JMSG_LENGTH_MAX];
  (*c->err->format_message)(c, buf);
  return buf;
}

void onJpegError(j_common_ptr c) {
  auto* e = reinterpret_cast<JpegErrors*>(c->err);
  e->message = formatted(c);
  std::longjmp(e->jump, 1);
}

void onJpegMessage(j_common_ptr c, int level) {  // nothing goes to stderr
  auto* e = reinterpret_cast<JpegErrors*>(c->err);
  if (level >= 0 || !meansDamagedData(c->err->msg_code)) return;
  if (e->refusing_warnings++ == 0) e->message = formatted(c);
}

/// What the libjpeg run works on: outside the function that calls setjmp, so that nothing it
/// changes is a local of that function (their values would be indeterminate after longjmp).
struct JpegRun {
  jpeg_decompress_struct cinfo{};
  JpegErrors errors{};
  cv::Mat out;
  bool fall_back = false;  ///< 4 components (CMYK / YCCK): left to OpenCV
};

/// false on a fatal libjpeg error (run.errors.message).
bool runLibjpeg(const uint8_t* d, size_t n, bool grey, JpegRun& run) {
  run.cinfo.err = jpeg_std_error(&run.errors.mgr);
  run.errors.mgr.error_exit = onJpegError;
  run.errors.mgr.emit_message = onJpegMessage;
  if (setjmp(run.errors.jump)) {
    jpeg_destroy_decompress(&run.cinfo);
    return false;
  }
  jpeg_create_decompress(&run.cinfo);
  jpeg_mem_src(&run.cinfo, d, static_cast<unsigned long>(n));
  jpeg_read_header(&run.cinfo, TRUE);
  if (run.cinfo.num_components == 4) {
    run.fall_back = true;
    jpeg_destroy_decompress(&run.cinfo);
    return true;
  }
  run.cinfo.out_color_space = grey || run.cinfo.num_components == 1 ? JCS_GRAYSCALE : JCS_EXT_BGR;
  jpeg_start_decompress(&run.cinfo);
  run.out.create(static_cast<int>(run.cinfo.output_height), static_cast<int>(run.cinfo.output_width),
                 CV_8UC(run.cinfo.output_components));
  while (run.cinfo.output_scanline < run.cinfo.output_height) {
    JSAMPROW row = run.out.ptr(static_cast<int>(run.cinfo.output_scanline));
    jpeg_read_scanlines(&run.cinfo, &row, 1);
  }
  jpeg_finish_decompress(&run.cinfo);
  jpeg_destroy_decompress(&run.cinfo);
  return true;
}

/// A JPEG decoded as cv::imdecode would (flags IMREAD_UNCHANGED, GRAYSCALE or COLOR), refused when
/// libjpeg fails or warns of damaged data. *fall_back: not handled here (CMYK), use OpenCV.
cv::Mat decodeJpegStrictly(const uint8_t* d, size_t n, int flags, bool* fall_back, std::string* why) {
  JpegRun run;
  const bool ok = runLibjpeg(d, n, flags == cv::IMREAD_GRAYSCALE, run);
  *fall_back = run.fall_back;
  if (ok && run.errors.refusing_warnings == 0) return run.out;
  if (why) {
    *why = "corrupt JPEG: libjpeg: " + run.errors.message;
    if (run.errors.refusing_warnings > 1)
      *why += " (and " + std::to_string(run.errors.refusing_warnings - 1) + " more warnings of damaged data)";
  }
  return cv::Mat();
}

/// HeaderProbe's bound on a side (its one row: at most 64 Ki px x 4 channels x 2 bytes = 512 KiB);
/// the default limits are far below.
constexpr int64_t kMaxProbeSidePx = int64_t{1} << 16;

}  // namespace

std::optional<std::string> checkLimits(const ImageHeader& h, const ImageLimits& lim) {
  if (h.width_px > lim.max_side_px || h.height_px > lim.max_side_px)
    return h.describe() + ": a side beyond the limit of " + std::to_string(lim.max_side_px) + " px";
  if (h.pixels() > lim.max_pixels)
    return h.describe() + ": " + std::to_string(h.pixels()) + " pixels, beyond the limit of " +
           std::to_string(lim.max_pixels);
  if (h.decodedBytes() > lim.max_decoded_bytes)
    return h.describe() + ": would decode into " + std::to_string(h.decodedBytes()) + " bytes, beyond the limit of " +
           std::to_string(lim.max_decoded_bytes);
  return std::nullopt;
}

bool isCorruption(ImageFault f) {
  return f == ImageFault::kHeader || f == ImageFault::kTruncated || f == ImageFault::kUndecodable;
}

Inspection inspectImage(const uint8_t* bytes, size_t size, const ImageLimits& limits, const HeaderCheck& check) {
  Inspection out;
  auto refuse = [&](ImageFault f, std::string why) {
    out.fault = f;
    out.error = std::move(why);
    return out;
  };
  auto parsed = readImageHeader(bytes, size);
  if (!parsed.header) return refuse(ImageFault::kHeader, parsed.error);
  out.header = parsed.header;
  if (auto why = checkLimits(*out.header, limits)) return refuse(ImageFault::kLimits, *why);
  if (auto bad = check ? check(*out.header) : std::nullopt) return refuse(ImageFault::kCheck, *bad);
  if (auto cut = checkComplete(*out.header, bytes, size)) return refuse(ImageFault::kTruncated, *cut);
  return out;
}

cv::Mat decodeInspected(const uint8_t* bytes, size_t size, const ImageHeader& h, int flags, std::string* why) {
  auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return cv::Mat();
  };
  if (size > static_cast<size_t>(INT32_MAX))
    return fail("encoded image of " + std::to_string(size) + " bytes: too large");
  cv::Mat img;
  const bool strict_jpeg =
      h.codec == ImageCodec::kJpeg && h.bit_depth == 8 &&
      (flags == cv::IMREAD_UNCHANGED || flags == cv::IMREAD_GRAYSCALE || flags == cv::IMREAD_COLOR);
  if (strict_jpeg) {
    bool fall_back = false;
    img = decodeJpegStrictly(bytes, size, flags, &fall_back, why);
    if (img.empty() && !fall_back) return img;
    if (!img.empty() && flags == cv::IMREAD_COLOR && img.channels() == 1) cv::cvtColor(img, img, cv::COLOR_GRAY2BGR);
  }
  if (flags >= 0) flags |= cv::IMREAD_IGNORE_ORIENTATION;
  if (img.empty()) {
    try {
      // A header over the caller's bytes (no copy); imdecode only reads it.
      const cv::Mat buf(1, static_cast<int>(size), CV_8U, const_cast<uint8_t*>(bytes));
      img = cv::imdecode(buf, flags);
    } catch (const cv::Exception& e) {  // never let a bad image escape into a callback
      return fail(std::string(codecName(h.codec)) + " does not decode: " + e.what());
    } catch (const std::exception& e) {
      return fail(std::string(codecName(h.codec)) + " does not decode: " + e.what());
    }
  }
  if (img.empty()) return fail(std::string(codecName(h.codec)) + " does not decode (" + h.describe() + ")");
  if (img.cols != h.width_px || img.rows != h.height_px)
    return fail("decoded size " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                " differs from the header's " + std::to_string(h.width_px) + "x" + std::to_string(h.height_px));
  const bool depth_ok = flags >= 0 && (flags & cv::IMREAD_ANYDEPTH) == 0
                            ? img.depth() == CV_8U
                            : img.depth() == (h.bytesPerChannel() == 1 ? CV_8U : CV_16U);
  if (!depth_ok) return fail("decoded depth differs from the header's (" + h.describe() + ")");
  return img;
}

DecodedImage decodeImageBytes(const uint8_t* bytes, size_t size, const DecodeOptions& opt) {
  DecodedImage out;
  Inspection ins = inspectImage(bytes, size, opt.limits, opt.check);
  out.header = ins.header;
  out.fault = ins.fault;
  out.error = ins.error;
  if (!ins.ok()) return out;
  out.image = decodeInspected(bytes, size, *ins.header, opt.flags, &out.error);
  if (out.image.empty()) out.fault = ImageFault::kUndecodable;
  return out;
}

std::optional<std::vector<uint8_t>> readFileBytes(const std::filesystem::path& path, int64_t max_bytes,
                                                  std::string* why) {
  auto fail = [&](const std::string& w) -> std::optional<std::vector<uint8_t>> {
    if (why) *why = w;
    return std::nullopt;
  };
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return fail("cannot read: " + ec.message());
  if (static_cast<uint64_t>(size) > static_cast<uint64_t>(max_bytes))
    return fail("file of " + std::to_string(size) + " bytes, beyond the limit of " + std::to_string(max_bytes));
  std::ifstream f(path, std::ios::binary);
  std::vector<uint8_t> bytes(static_cast<size_t>(size));
  if (!f || !f.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size)))
    return fail("cannot read the file's " + std::to_string(size) + " bytes");
  return bytes;
}

DecodedImage readImageFile(const std::filesystem::path& path, const DecodeOptions& opt) {
  DecodedImage out;
  const auto bytes = readFileBytes(path, opt.limits.max_encoded_bytes, &out.error);
  if (!bytes) {
    out.fault = ImageFault::kFile;
    return out;
  }
  return decodeImageBytes(bytes->data(), bytes->size(), opt);
}

HeaderProbe::HeaderProbe(const ImageHeader& h) {
  if (h.width_px < 1 || h.height_px < 1 || h.width_px > kMaxProbeSidePx || h.height_px > kMaxProbeSidePx)
    throw std::invalid_argument("HeaderProbe of " + h.describe() + ": check the header's limits first");
  const int depth = h.bytesPerChannel() == 1 ? CV_8U : CV_16U;
  const int channels = h.channels < 1 ? 1 : h.channels > 4 ? 4 : h.channels;
  const int type = CV_MAKETYPE(depth, channels);
  const int sizes[2] = {static_cast<int>(h.height_px), static_cast<int>(h.width_px)};
  row_.assign(static_cast<size_t>(h.width_px) * CV_ELEM_SIZE(type), 0);
  const size_t steps[1] = {0};  // every row is row_
  image_ = cv::Mat(2, sizes, type, row_.data(), steps);
}

}  // namespace omnislam::vision
