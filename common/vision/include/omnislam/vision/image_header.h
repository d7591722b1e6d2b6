// What an encoded image says about itself before it is decoded: size, channels and bit depth from
// the header of a PNG, JPEG (baseline, extended, progressive, lossless), BMP or PGM/PPM/PBM, and
// whether its bytes end where the format says they must (a truncated JPEG or PNG). Pure byte
// parsing, no pixel decoded, no allocation beyond the result: a decompression bomb is refused on
// these figures before OpenCV allocates its pixels (image_decode.h, docs/user/messages.md "Images").
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace omnislam::vision {

enum class ImageCodec { kPng, kJpeg, kBmp, kPnm };

/// "PNG", "JPEG", "BMP", "PNM".
const char* codecName(ImageCodec codec);

struct ImageHeader {
  ImageCodec codec = ImageCodec::kPng;
  int64_t width_px = 0;   ///< columns, >= 1
  int64_t height_px = 0;  ///< rows, >= 1 (a BMP's negative, top-down height as its magnitude)
  /// Channels of the image cv::imdecode(IMREAD_UNCHANGED) makes of it (OpenCV 4.6's rules): 1 grey;
  /// 3 colour (a PNG or BMP palette: 3 unless a BMP's palette is all grey; JPEG with 3 or 4
  /// components); 4 with alpha (PNG grey+alpha, RGBA, or RGB / palette with a tRNS chunk; BMP 32-bit
  /// with bit fields).
  int channels = 0;
  int bit_depth = 0;         ///< bits per channel as stored: 1, 2, 4, 8, 12 (JPEG) or 16
  bool progressive = false;  ///< JPEG: a multi-scan frame (SOF2, 6, 10, 14)
  /// BMP and binary PNM with uncompressed pixels: bytes the data must hold for all of them (0 when
  /// the header does not fix it: ASCII PNM, RLE BMP, PNG, JPEG).
  int64_t raster_end_bytes = 0;

  int64_t pixels() const { return width_px * height_px; }
  /// Bytes per channel of the decoded image: 1 for <= 8 bits, else 2 (OpenCV's CV_8U / CV_16U).
  int bytesPerChannel() const { return bit_depth <= 8 ? 1 : 2; }
  /// Bytes of the decoded image (IMREAD_UNCHANGED): pixels x channels x bytes per channel.
  int64_t decodedBytes() const { return pixels() * channels * bytesPerChannel(); }
  /// "8192x8192, 1 channel, 16-bit PNG".
  std::string describe() const;
};

struct HeaderResult {
  std::optional<ImageHeader> header;
  std::string error;  ///< why there is no header (one line), when there is none
};

/// The header of the encoded image in bytes[0, size): the format is recognised by its signature,
/// not by a file name. Anything else (another format, too few bytes, a field out of range, a
/// segment or chunk running past the end before the size is known) gives an error, never a throw.
HeaderResult readImageHeader(const uint8_t* bytes, size_t size);

/// Whether bytes[0, size) hold the whole encoded image `header` was read from: nothing if they do,
/// else the reason. JPEG: the marker segments and the entropy-coded data of every scan are walked to
/// the end-of-image marker (EOI; a file without it is what libjpeg decodes anyway after printing
/// "Premature end of JPEG file", the missing part grey); bytes after EOI are allowed (camera
/// trailers). PNG: the chunks are walked to IEND. BMP and binary PNM: raster_end_bytes must fit.
/// ASCII PNM and RLE BMP are not checked (OpenCV's decoder reports their truncation).
std::optional<std::string> checkComplete(const ImageHeader& header, const uint8_t* bytes, size_t size);

}  // namespace omnislam::vision
