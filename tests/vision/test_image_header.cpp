// The encoded-image header parser and checked decoding (vision/image_header.h, image_decode.h):
// headers of files written by cv::imencode in every format, depth and channel count the project
// reads agree with what cv::imdecode makes of them; truncations, garbage and seeded corruptions
// never crash and never pass as complete; huge claimed sizes are refused before decoding; a
// truncated JPEG, which cv::imdecode decodes anyway, is refused.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include <random>
#include <string>
#include <vector>

#include "omnislam/vision/image_decode.h"
#include "omnislam/vision/image_header.h"

using namespace omnislam::vision;

namespace {

struct Case {
  std::string ext;
  int type;
  std::vector<int> params;
  ImageCodec codec;
};

std::vector<Case> cases() {
  const std::vector<int> none, progressive{cv::IMWRITE_JPEG_PROGRESSIVE, 1}, binary{cv::IMWRITE_PXM_BINARY, 1},
      ascii{cv::IMWRITE_PXM_BINARY, 0};
  return {{".png", CV_8UC1, none, ImageCodec::kPng},         {".png", CV_8UC3, none, ImageCodec::kPng},
          {".png", CV_8UC4, none, ImageCodec::kPng},         {".png", CV_16UC1, none, ImageCodec::kPng},
          {".png", CV_16UC3, none, ImageCodec::kPng},        {".png", CV_16UC4, none, ImageCodec::kPng},
          {".jpg", CV_8UC1, none, ImageCodec::kJpeg},        {".jpg", CV_8UC3, none, ImageCodec::kJpeg},
          {".jpg", CV_8UC1, progressive, ImageCodec::kJpeg}, {".jpg", CV_8UC3, progressive, ImageCodec::kJpeg},
          {".bmp", CV_8UC1, none, ImageCodec::kBmp},         {".bmp", CV_8UC3, none, ImageCodec::kBmp},
          {".bmp", CV_8UC4, none, ImageCodec::kBmp},         {".pgm", CV_8UC1, binary, ImageCodec::kPnm},
          {".pgm", CV_16UC1, binary, ImageCodec::kPnm},      {".ppm", CV_8UC3, binary, ImageCodec::kPnm},
          {".ppm", CV_16UC3, binary, ImageCodec::kPnm},      {".pgm", CV_8UC1, ascii, ImageCodec::kPnm},
          {".ppm", CV_8UC3, ascii, ImageCodec::kPnm},        {".pbm", CV_8UC1, binary, ImageCodec::kPnm}};
}

std::string name(const Case& c) {
  return c.ext + " " + cv::typeToString(c.type) + (c.params.empty() ? "" : " p" + std::to_string(c.params[1]));
}

std::vector<uint8_t> encode(const Case& c, int cols = 37, int rows = 23, uint64_t seed = 1) {
  cv::Mat img(rows, cols, c.type);
  cv::RNG rng(seed);
  rng.fill(img, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(c.type) == CV_16U ? 65535 : 255);
  std::vector<uint8_t> buf;
  EXPECT_TRUE(cv::imencode(c.ext, img, buf, c.params)) << name(c);
  return buf;
}

TEST(ImageHeader, AgreesWithWhatImdecodeMakesOfEveryFormatDepthAndChannelCount) {
  for (const Case& c : cases()) {
    const auto buf = encode(c);
    const auto r = readImageHeader(buf.data(), buf.size());
    ASSERT_TRUE(r.header.has_value()) << name(c) << ": " << r.error;
    const ImageHeader& h = *r.header;
    const cv::Mat img = cv::imdecode(buf, cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(img.empty()) << name(c);
    EXPECT_EQ(h.codec, c.codec) << name(c);
    EXPECT_EQ(h.width_px, 37) << name(c);
    EXPECT_EQ(h.height_px, 23) << name(c);
    EXPECT_EQ(h.channels, img.channels()) << name(c);
    EXPECT_EQ(h.bytesPerChannel(), static_cast<int>(img.elemSize1())) << name(c);
    EXPECT_EQ(h.decodedBytes(), static_cast<int64_t>(img.total() * img.elemSize())) << name(c);
    EXPECT_EQ(h.progressive, c.ext == ".jpg" && !c.params.empty()) << name(c);
    EXPECT_FALSE(checkComplete(h, buf.data(), buf.size()).has_value()) << name(c);
    const DecodedImage d = decodeImageBytes(buf.data(), buf.size());
    EXPECT_TRUE(d.ok()) << name(c) << ": " << d.error;
    EXPECT_EQ(cv::norm(d.image, img, cv::NORM_INF), 0.0) << name(c);
  }
}

// Every prefix of every file: never a crash; a prefix with a header is never complete (the
// ASCII PNM, whose raster has no fixed length, excepted: OpenCV reports its truncation).
TEST(ImageHeader, EveryTruncationIsRefusedOrReportedIncomplete) {
  for (const Case& c : cases()) {
    const auto buf = encode(c, 19, 11);
    const bool ascii_pnm = c.codec == ImageCodec::kPnm && c.params[1] == 0;
    for (size_t n = 0; n < buf.size(); ++n) {
      const auto r = readImageHeader(buf.data(), n);
      if (!r.header) {
        EXPECT_FALSE(r.error.empty()) << name(c) << " prefix " << n;
        continue;
      }
      if (ascii_pnm) continue;
      EXPECT_TRUE(checkComplete(*r.header, buf.data(), n).has_value())
          << name(c) << " prefix " << n << " of " << buf.size();
      EXPECT_FALSE(decodeImageBytes(buf.data(), n).ok()) << name(c) << " prefix " << n;
    }
  }
}

void expectSane(const HeaderResult& r, const std::string& what) {
  if (!r.header) {
    EXPECT_FALSE(r.error.empty()) << what;
    return;
  }
  const ImageHeader& h = *r.header;
  EXPECT_GE(h.width_px, 1) << what;
  EXPECT_GE(h.height_px, 1) << what;
  EXPECT_LE(h.width_px, int64_t{1} << 24) << what;
  EXPECT_LE(h.height_px, int64_t{1} << 24) << what;
  EXPECT_TRUE(h.channels == 1 || h.channels == 3 || h.channels == 4) << what;
  EXPECT_TRUE(h.bit_depth >= 1 && h.bit_depth <= 16) << what;
  EXPECT_GT(h.decodedBytes(), 0) << what;
}

// Random bytes, random bytes behind each format's signature, and seeded corruptions (bytes changed
// in the first 64, then maybe truncated) of every valid file: the parser and the completeness check
// return (a result or a reason) and what they return is in range. Run under the sanitizers by
// scripts/run-tests.sh with OMNISLAM_SANITIZE.
TEST(ImageHeader, FuzzedBytesNeverCrashAndGiveSaneFigures) {
  std::mt19937 rng(20261126);
  const std::vector<std::vector<uint8_t>> signatures = {
      {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R'},
      {0xFF, 0xD8, 0xFF},
      {'B', 'M'},
      {'P', '5'},
      {'P', '6', ' '},
      {'P', '4', '\n'},
      {'P', '1'}};
  for (int trial = 0; trial < 20000; ++trial) {
    std::vector<uint8_t> d(std::uniform_int_distribution<size_t>(0, 300)(rng));
    for (auto& b : d) b = static_cast<uint8_t>(rng());
    const auto& sig = signatures[static_cast<size_t>(trial) % signatures.size()];
    if (trial % 2 == 0 && d.size() >= sig.size()) std::copy(sig.begin(), sig.end(), d.begin());
    const auto r = readImageHeader(d.data(), d.size());
    expectSane(r, "random trial " + std::to_string(trial));
    if (r.header) checkComplete(*r.header, d.data(), d.size());
  }
  int refused = 0, total = 0;
  for (const Case& c : cases()) {
    const auto good = encode(c, 23, 17);
    for (int trial = 0; trial < 300; ++trial, ++total) {
      auto d = good;
      const int edits = 1 + trial % 4;
      for (int e = 0; e < edits; ++e)
        d[std::uniform_int_distribution<size_t>(0, std::min<size_t>(63, d.size() - 1))(rng)] =
            static_cast<uint8_t>(rng());
      if (trial % 3 == 0) d.resize(std::uniform_int_distribution<size_t>(0, d.size())(rng));
      const auto r = readImageHeader(d.data(), d.size());
      expectSane(r, name(c) + " trial " + std::to_string(trial));
      DecodedImage out;
      ASSERT_NO_THROW(out = decodeImageBytes(d.data(), d.size())) << name(c) << " trial " << trial;
      refused += out.ok() ? 0 : 1;
      if (out.ok()) {
        EXPECT_EQ(out.image.cols, out.header->width_px);
        EXPECT_EQ(out.image.rows, out.header->height_px);
      }
    }
  }
  EXPECT_GT(refused, total / 4) << "the corruptions must reach the refusals";
}

uint32_t crc32(const uint8_t* p, size_t n) {
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return c ^ 0xFFFFFFFFu;
}

void putBigEndian(std::vector<uint8_t>& d, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) d[at + static_cast<size_t>(i)] = static_cast<uint8_t>(v >> (24 - 8 * i));
}

// A PNG whose IHDR says w x h, otherwise well formed (its CRC recomputed).
std::vector<uint8_t> pngClaiming(uint32_t w, uint32_t h, int depth = 8) {
  std::vector<uint8_t> d;
  cv::imencode(".png", cv::Mat(4, 4, CV_8UC1, cv::Scalar(3)), d);
  putBigEndian(d, 16, w);
  putBigEndian(d, 20, h);
  d[24] = static_cast<uint8_t>(depth);
  putBigEndian(d, 29, crc32(d.data() + 12, 17));
  return d;
}

TEST(ImageHeader, HugeClaimedSizesAreRefusedBeforeDecoding) {
  const ImageLimits lim;
  // Within what a header may say, beyond the limits: refused as kLimits with the figures.
  auto big = pngClaiming(60000, 60000);
  auto d = decodeImageBytes(big.data(), big.size());
  EXPECT_EQ(d.fault, ImageFault::kLimits);
  EXPECT_EQ(d.error, "60000x60000, 1 channel, 8-bit PNG: a side beyond the limit of 8192 px");
  auto bomb = pngClaiming(8192, 8192, 16);
  d = decodeImageBytes(bomb.data(), bomb.size());
  EXPECT_EQ(d.fault, ImageFault::kLimits);
  EXPECT_EQ(d.error,
            "8192x8192, 1 channel, 16-bit PNG: would decode into 134217728 bytes, beyond the limit of 67108864");
  // Beyond anything real: the header itself is refused.
  auto absurd = pngClaiming(0x7fffffffu, 0x7fffffffu);
  EXPECT_EQ(readImageHeader(absurd.data(), absurd.size()).error,
            "PNG header claims 2147483647x2147483647 px: a side outside 1..2^24");
  auto zero = pngClaiming(0, 5);
  EXPECT_FALSE(readImageHeader(zero.data(), zero.size()).header.has_value());
  // JPEG: the frame header's 16-bit sides at their largest.
  std::vector<uint8_t> j;
  cv::imencode(".jpg", cv::Mat(8, 8, CV_8UC1, cv::Scalar(3)), j);
  size_t sof = 2;
  while (sof + 9 < j.size() && !(j[sof] == 0xFF && j[sof + 1] == 0xC0)) ++sof;
  ASSERT_LT(sof + 9, j.size());
  j[sof + 5] = j[sof + 6] = j[sof + 7] = j[sof + 8] = 0xFF;
  d = decodeImageBytes(j.data(), j.size());
  EXPECT_EQ(d.fault, ImageFault::kLimits);
  EXPECT_EQ(d.error, "65535x65535, 1 channel, 8-bit JPEG: a side beyond the limit of 8192 px");
  // PGM and BMP.
  const std::string pgm = "P5\n# a comment\n100000 100000\n255\n";
  d = decodeImageBytes(reinterpret_cast<const uint8_t*>(pgm.data()), pgm.size());
  EXPECT_EQ(d.fault, ImageFault::kLimits);
  std::vector<uint8_t> bmp;
  cv::imencode(".bmp", cv::Mat(4, 4, CV_8UC3, cv::Scalar(3)), bmp);
  bmp[18] = bmp[19] = bmp[20] = 0, bmp[21] = 0x40;  // width 2^30
  EXPECT_FALSE(readImageHeader(bmp.data(), bmp.size()).header.has_value());
  bmp[21] = 0, bmp[19] = 0x30;  // 12288: a side beyond the limit
  d = decodeImageBytes(bmp.data(), bmp.size());
  EXPECT_EQ(d.fault, ImageFault::kLimits) << d.error;
  // A tighter pixel limit is applied as given.
  ImageLimits small;
  small.max_pixels = 37 * 23 - 1;
  const auto ok = encode(cases()[0]);
  ASSERT_TRUE(readImageHeader(ok.data(), ok.size()).header);
  EXPECT_TRUE(checkLimits(*readImageHeader(ok.data(), ok.size()).header, small).has_value());
  EXPECT_FALSE(checkLimits(*readImageHeader(ok.data(), ok.size()).header, lim).has_value());
}

// A baseline JPEG cut short is what libjpeg decodes anyway ("Premature end of JPEG file" on
// stderr, the missing rows grey): cv::imdecode returns a full-size image. (A progressive one cut at
// 60 % comes back empty from this OpenCV.) The EOI walk refuses both.
TEST(ImageHeader, ATruncatedJpegThatImdecodeAcceptsIsRefused) {
  cv::Mat img(240, 320, CV_8UC3);
  cv::randu(img, 0, 255);
  for (const bool progressive : {false, true}) {
    std::vector<uint8_t> buf;
    cv::imencode(".jpg", img, buf, {cv::IMWRITE_JPEG_PROGRESSIVE, progressive ? 1 : 0});
    auto cut = buf;
    cut.resize(buf.size() * 6 / 10);
    const cv::Mat lenient = cv::imdecode(cut, cv::IMREAD_UNCHANGED);
    if (!progressive) {
      EXPECT_FALSE(lenient.empty()) << "OpenCV decodes a truncated JPEG (the case this check is for)";
    }
    const DecodedImage d = decodeImageBytes(cut.data(), cut.size());
    EXPECT_EQ(d.fault, ImageFault::kTruncated) << progressive;
    EXPECT_TRUE(isCorruption(d.fault));
    EXPECT_EQ(d.error.rfind(
                  "truncated JPEG: no end-of-image marker (EOI) in its " + std::to_string(cut.size()) + " bytes", 0),
              0u)
        << d.error;
    // Bytes after EOI (camera trailers) are allowed; the last byte of EOI missing is not.
    auto trailer = buf;
    trailer.insert(trailer.end(), {0x00, 0x11, 0xFF, 0x22});
    EXPECT_TRUE(decodeImageBytes(trailer.data(), trailer.size()).ok());
    auto no_eoi = buf;
    no_eoi.pop_back();
    EXPECT_EQ(decodeImageBytes(no_eoi.data(), no_eoi.size()).fault, ImageFault::kTruncated);
  }
}

// A JPEG whose scan lost a block of its data but still ends with EOI (a copy that dropped bytes):
// cv::imdecode returns it with invented blocks, libjpeg's "premature end of data segment" on
// stderr the only trace. decodeImageBytes decodes JPEGs with libjpeg itself and refuses it.
TEST(ImageHeader, AJpegWithDamagedScanDataIsRefusedWithLibjpegsReason) {
  cv::Mat img(240, 320, CV_8UC3);
  cv::randu(img, 0, 255);
  std::vector<uint8_t> buf;
  cv::imencode(".jpg", img, buf);
  auto cut = buf;
  cut.erase(cut.begin() + static_cast<std::ptrdiff_t>(buf.size() / 2),
            cut.begin() + static_cast<std::ptrdiff_t>(buf.size() / 2 + buf.size() / 4));
  ASSERT_FALSE(checkComplete(*readImageHeader(cut.data(), cut.size()).header, cut.data(), cut.size()).has_value())
      << "still ends with EOI";
  EXPECT_FALSE(cv::imdecode(cut, cv::IMREAD_UNCHANGED).empty()) << "OpenCV decodes it (the case this check is for)";
  const DecodedImage d = decodeImageBytes(cut.data(), cut.size());
  EXPECT_EQ(d.fault, ImageFault::kUndecodable);
  EXPECT_EQ(d.error, "corrupt JPEG: libjpeg: Corrupt JPEG data: premature end of data segment");
}

// The JPEGs decoded through libjpeg directly are exactly what cv::imdecode makes, for each flag.
TEST(ImageHeader, JpegsDecodeAsImdecodeDecodesThem) {
  for (const Case& c : cases()) {
    if (c.codec != ImageCodec::kJpeg) continue;
    const auto buf = encode(c, 64, 48);
    for (const int flags : {cv::IMREAD_UNCHANGED, cv::IMREAD_GRAYSCALE, cv::IMREAD_COLOR}) {
      DecodeOptions opt;
      opt.flags = flags;
      const DecodedImage d = decodeImageBytes(buf.data(), buf.size(), opt);
      ASSERT_TRUE(d.ok()) << name(c) << " flags " << flags << ": " << d.error;
      const cv::Mat ref = cv::imdecode(buf, flags);
      ASSERT_EQ(d.image.type(), ref.type()) << name(c) << " flags " << flags;
      EXPECT_EQ(cv::norm(d.image, ref, cv::NORM_INF), 0.0) << name(c) << " flags " << flags;
    }
  }
}

// OpenCV gives an RGB or palette PNG with a tRNS chunk an alpha channel; the header says so too.
TEST(ImageHeader, APngTransparencyChunkAddsTheAlphaChannel) {
  std::vector<uint8_t> d;
  cv::imencode(".png", cv::Mat(5, 7, CV_8UC3, cv::Scalar(1, 2, 3)), d);
  const std::vector<uint8_t> chunk_type_and_data = {'t', 'R', 'N', 'S', 0, 1, 0, 2, 0, 3};  // RGB key colour
  std::vector<uint8_t> chunk(4 + chunk_type_and_data.size() + 4);
  putBigEndian(chunk, 0, 6);
  std::copy(chunk_type_and_data.begin(), chunk_type_and_data.end(), chunk.begin() + 4);
  putBigEndian(chunk, chunk.size() - 4, crc32(chunk_type_and_data.data(), chunk_type_and_data.size()));
  d.insert(d.begin() + 33, chunk.begin(), chunk.end());  // after IHDR (8 + 25 bytes)
  const auto r = readImageHeader(d.data(), d.size());
  ASSERT_TRUE(r.header) << r.error;
  const cv::Mat img = cv::imdecode(d, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(r.header->channels, img.channels());
  EXPECT_EQ(r.header->channels, 4);
}

TEST(ImageHeader, OtherFormatsAndUnknownBytesAreRefusedWithAReason) {
  std::vector<uint8_t> tiff;
  ASSERT_TRUE(cv::imencode(".tiff", cv::Mat(4, 4, CV_8UC1, cv::Scalar(3)), tiff));
  EXPECT_EQ(readImageHeader(tiff.data(), tiff.size()).error,
            "not a PNG, JPEG, BMP or PGM/PPM/PBM image (unknown signature)");
  EXPECT_EQ(readImageHeader(nullptr, 0).error, "image of 0 bytes: no header");
  const uint8_t sos_first[] = {0xFF, 0xD8, 0xFF, 0xDA, 0, 2};
  EXPECT_EQ(readImageHeader(sos_first, sizeof sos_first).error,
            "JPEG: marker 0xFFDA at byte 3 before any frame header");
}

// The stand-in for a header's image costs one row, whatever its height, and reads as zeros.
TEST(ImageHeader, AHeaderProbeHasTheDimensionsButOneRowOfMemory) {
  ImageHeader h;
  h.width_px = 8192, h.height_px = 8192, h.channels = 1, h.bit_depth = 16;
  const HeaderProbe probe(h);
  const cv::Mat& m = probe.image();
  EXPECT_EQ(m.cols, 8192);
  EXPECT_EQ(m.rows, 8192);
  EXPECT_EQ(m.type(), CV_16UC1);
  EXPECT_FALSE(m.empty());
  EXPECT_EQ(m.step[0], 0u);
  EXPECT_EQ(m.at<uint16_t>(8191, 8191), 0);
  h.channels = 3, h.bit_depth = 8;
  EXPECT_EQ(HeaderProbe(h).image().type(), CV_8UC3);
}

}  // namespace
