// Decoding encoded images (bytes of an OMNI_IMAGE message, image files) with their header read and
// checked first (image_header.h): a header beyond the limits, an image the consumer cannot use
// (the camera's size, 8 bits) and a truncated JPEG or PNG are refused with a one-line reason before
// OpenCV allocates any pixel. Every path of the project that decodes image bytes goes through here:
// lcmio::decodeImage (OMNI_IMAGE), omnislam-features --images, omnislam-capture --source dir
// (docs/user/messages.md, "Images: what is refused before decoding").
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/vision/image_header.h"

namespace omnislam::vision {

/// What any decoder here accepts at most, whatever the consumer. The defaults are the largest
/// frame the message contract carries (lcmio::Limits: sides up to 8192 px, 64 MiB of data): a
/// compressed frame may not decode into more than the same frame could carry uncompressed. The
/// largest camera the project is configured for is 1280 x 960 (the OpenCV omnidir samples), 4.8 %
/// of this; consumers that know their camera refuse anything else through their HeaderCheck.
struct ImageLimits {
  int64_t max_side_px = 8192;                     ///< width and height at most this
  int64_t max_pixels = int64_t{8192} * 8192;      ///< 67 108 864: an 8192 x 8192 frame
  int64_t max_decoded_bytes = int64_t{64} << 20;  ///< pixels x channels x bytes per channel
  int64_t max_encoded_bytes = int64_t{64} << 20;  ///< a file larger than this is not read
};

/// Why `header` exceeds `limits`, or nothing.
std::optional<std::string> checkLimits(const ImageHeader& header, const ImageLimits& limits);

/// A consumer's check of the header before decoding (the camera's size, a bit depth): the reason
/// to refuse, or nothing.
using HeaderCheck = std::function<std::optional<std::string>(const ImageHeader&)>;

/// Why encoded bytes were refused: for counting (a consumer's mismatch is not a corrupt file).
enum class ImageFault {
  kNone,
  kFile,        ///< readImageFile: the file cannot be read, or is larger than max_encoded_bytes
  kHeader,      ///< no readable header: unknown format, malformed or truncated header
  kLimits,      ///< beyond ImageLimits
  kCheck,       ///< the consumer's HeaderCheck refused it (its camera's size, depth, channels)
  kTruncated,   ///< checkComplete: the data ends early (no JPEG EOI, no PNG IEND, short raster)
  kUndecodable  ///< the decoder failed or reported damaged data, or made another size than the header
};

/// True for the faults of a damaged file or message (header, truncated, undecodable).
bool isCorruption(ImageFault fault);

struct Inspection {
  std::optional<ImageHeader> header;  ///< set when the header was read (also when refused after)
  std::string error;                  ///< why the bytes are refused; empty when they may be decoded
  ImageFault fault = ImageFault::kNone;
  bool ok() const { return fault == ImageFault::kNone; }
};

/// Reads the header of bytes[0, size) and refuses them, in this order, when it cannot be read, is
/// beyond `limits`, fails `check` (when given) or the bytes are incomplete (checkComplete).
Inspection inspectImage(const uint8_t* bytes, size_t size, const ImageLimits& limits = {},
                        const HeaderCheck& check = nullptr);

/// Decodes inspected bytes as cv::imdecode does with `flags` (IMREAD_*; EXIF orientation is ignored:
/// camera frames stay in sensor pixels). An 8-bit JPEG (1 or 3 components; flags UNCHANGED,
/// GRAYSCALE or COLOR) is decoded by libjpeg directly, with OpenCV's settings (identical output),
/// and refused when libjpeg warns of damaged data (premature end of data segment, bad Huffman code,
/// premature end of file, resync, bogus progression), which OpenCV only prints. Never throws: an
/// empty Mat and *why when the data is refused or the image is not the header's size and depth.
cv::Mat decodeInspected(const uint8_t* bytes, size_t size, const ImageHeader& header, int flags, std::string* why);

struct DecodeOptions {
  ImageLimits limits;
  HeaderCheck check;                 ///< null: no check beyond the limits
  int flags = cv::IMREAD_UNCHANGED;  ///< passed to cv::imdecode
};

struct DecodedImage {
  cv::Mat image;                      ///< empty when refused
  std::optional<ImageHeader> header;  ///< when it could be read
  std::string error;                  ///< why it was refused (one line); empty when decoded
  ImageFault fault = ImageFault::kNone;
  bool ok() const { return fault == ImageFault::kNone; }
};

/// inspectImage, then decodeInspected.
DecodedImage decodeImageBytes(const uint8_t* bytes, size_t size, const DecodeOptions& options = {});

/// The bytes of a file; nothing and *why when it cannot be read or is larger than max_bytes (its
/// size is read first: a huge file is not loaded).
std::optional<std::vector<uint8_t>> readFileBytes(const std::filesystem::path& path, int64_t max_bytes,
                                                  std::string* why);

/// readFileBytes (limits.max_encoded_bytes), then decodeImageBytes. The error names no file: the
/// caller reports it with the name.
DecodedImage readImageFile(const std::filesystem::path& path, const DecodeOptions& options = {});

/// A stand-in for the image a header describes (its rows, columns, channels and depth: CV_8U or
/// CV_16U), for a consumer's size and format check written for cv::Mat (e.g. features::Detector::
/// check) before decoding. Every row is the same row of zeros (step[0] = 0), so it costs one row:
/// at most max_side_px x 4 channels x 2 bytes (64 KiB) after checkLimits. Read-only; its pixels are
/// meaningless.
struct HeaderProbe {
  /// Throws std::invalid_argument for a side outside 1..65536 (check the limits first).
  explicit HeaderProbe(const ImageHeader& header);
  HeaderProbe(const HeaderProbe&) = delete;
  HeaderProbe& operator=(const HeaderProbe&) = delete;
  const cv::Mat& image() const { return image_; }

 private:
  std::vector<uint8_t> row_;
  cv::Mat image_;
};

}  // namespace omnislam::vision
