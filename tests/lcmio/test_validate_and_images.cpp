// Message validation rules and image_t <-> cv::Mat round trips.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

#include "omnislam/lcmio/image_msg.h"
#include "omnislam/lcmio/validate.h"

using namespace omnislam;

namespace {

TEST(Validate, ImageSizesAndFormats) {
  image_t m{};
  m.width = 4, m.height = 2, m.row_stride = 4, m.pixel_format = image_t::FORMAT_GRAY8;
  m.data.assign(8, 0), m.size = 8;
  EXPECT_FALSE(lcmio::validate(m).has_value());
  m.row_stride = 3, m.size = 6, m.data.resize(6);  // only the stride rule is broken
  EXPECT_EQ(lcmio::validate(m).value_or(""), "row_stride 3 < width * channels");
  m.row_stride = 4, m.size = 7, m.data.resize(7);
  EXPECT_TRUE(lcmio::validate(m).has_value());
  m.size = 8, m.data.resize(8), m.pixel_format = 9;
  EXPECT_NE(lcmio::validate(m)->find("pixel_format"), std::string::npos);
  m.pixel_format = image_t::FORMAT_GRAY8, m.width = 100000;
  EXPECT_NE(lcmio::validate(m)->find("image size"), std::string::npos);
  // A compressed image has no row stride: the contract says 0.
  m.width = 4, m.pixel_format = image_t::FORMAT_PNG, m.row_stride = 0;
  EXPECT_FALSE(lcmio::validate(m).has_value());
  m.row_stride = 4;
  EXPECT_EQ(lcmio::validate(m).value_or(""), "row_stride 4 must be 0 for a compressed image");
}

TEST(Validate, FeaturesNeedFiniteAnglesAndPositiveCovariance) {
  features_t f{};
  f.num_features = 1;
  feature_t ft{};
  ft.kind = feature_t::KIND_CEILING_LIGHT, ft.has_elevation = true, ft.azimuth_rad = 1.0, ft.elevation_rad = 0.5;
  ft.covariance[0][0] = ft.covariance[1][1] = 1e-4;
  f.features = {ft};
  EXPECT_FALSE(lcmio::validate(f).has_value());
  f.features[0].azimuth_rad = NAN;
  EXPECT_TRUE(lcmio::validate(f).has_value());
  f.features[0].azimuth_rad = 4.0;
  EXPECT_NE(lcmio::validate(f)->find("azimuth"), std::string::npos);
  f.features[0].azimuth_rad = 1.0, f.features[0].covariance[1][1] = -1;
  EXPECT_NE(lcmio::validate(f)->find("positive definite"), std::string::npos);
  f.features[0].covariance[1][1] = 1e-4, f.features[0].kind = 7;
  EXPECT_NE(lcmio::validate(f)->find("kind"), std::string::npos);
  f.features[0].kind = feature_t::KIND_CEILING_LIGHT, f.camera_position_m[0] = INFINITY;
  EXPECT_NE(lcmio::validate(f)->find("camera_position_m"), std::string::npos);
  f.camera_position_m[0] = 0.0;
  // Azimuths are wrapped to (-pi, pi]; -pi, atan2's answer for y = -0, is the same direction.
  f.features[0].azimuth_rad = -M_PI;
  EXPECT_FALSE(lcmio::validate(f).has_value());
  f.features[0].azimuth_rad = -M_PI - 1e-6;
  EXPECT_NE(lcmio::validate(f).value_or("").find("azimuth outside"), std::string::npos);
  // A feature without elevation has elevation 0; anything else is a producer's error.
  f.features[0] = ft;
  f.features[0].kind = feature_t::KIND_VERTICAL_LINE, f.features[0].has_elevation = false;
  EXPECT_EQ(lcmio::validate(f).value_or(""), "feature 0: elevation given with has_elevation false");
  f.features[0].elevation_rad = 0.0;
  EXPECT_FALSE(lcmio::validate(f).has_value());
  // A non-symmetric covariance: the filter's paths would each read another matrix (FastSLAM 2.0
  // saw a negative determinant and never associated the measurement); rounding is tolerated.
  f.features[0] = ft;
  f.features[0].covariance[0][1] = 1e-3;
  EXPECT_EQ(lcmio::validate(f).value_or(""), "feature 0: covariance not symmetric");
  f.features[0].covariance[0][1] = 2e-5, f.features[0].covariance[1][0] = 2e-5 * (1 + 1e-12);
  EXPECT_FALSE(lcmio::validate(f).has_value());
  // Colours are 0..255 (a float of 3e38 would overflow a landmark's running mean to inf).
  f.features[0] = ft;
  f.features[0].colour_b[2] = 3e38f;
  EXPECT_EQ(lcmio::validate(f).value_or(""), "feature 0: colour outside 0..255");
  f.features[0].colour_b[2] = NAN;
  EXPECT_EQ(lcmio::validate(f).value_or(""), "feature 0: colour outside 0..255");
  f.features[0].colour_b[2] = 255.0f;
  EXPECT_FALSE(lcmio::validate(f).has_value());
}

TEST(Validate, PosesAndOdometryMustBeFinite) {
  pose_t p{};
  EXPECT_FALSE(lcmio::validate(p).has_value());
  p.covariance[2][1] = NAN;
  EXPECT_TRUE(lcmio::validate(p).has_value());
  odometry_t o{};
  o.omega_radps = INFINITY;
  EXPECT_TRUE(lcmio::validate(o).has_value());
}

// The contract's enums and covariances: a covariance must be symmetric (to rounding) with no negative
// variance (zero, as ground truth has it, is fine); a landmark's kind and type, a status's state and
// a particle's weight must be values the contract defines.
TEST(Validate, CovariancesEnumsAndWeightsAsTheContractDefinesThem) {
  pose_t p{};
  p.covariance[0][0] = 0.04;
  p.covariance[0][1] = p.covariance[1][0] = 0.01 + 1e-18;  // rounding
  EXPECT_FALSE(lcmio::validate(p).has_value());
  p.covariance[1][0] = 0.02;
  EXPECT_NE(lcmio::validate(p).value_or("").find("not symmetric"), std::string::npos);
  p.covariance[1][0] = p.covariance[0][1];
  p.covariance[2][2] = -1e-6;
  EXPECT_NE(lcmio::validate(p).value_or("").find("negative variance"), std::string::npos);
  p.covariance[2][2] = 0.0;
  p.effective_sample_size = -1.0;
  EXPECT_NE(lcmio::validate(p).value_or("").find("effective_sample_size"), std::string::npos);

  map_t m{};
  m.num_landmarks = 1;
  m.landmarks.resize(1);
  m.landmarks[0].kind = feature_t::KIND_CEILING_LIGHT;
  EXPECT_FALSE(lcmio::validate(m).has_value());  // truth: type 0, covariance 0
  m.landmarks[0].type = 2;
  EXPECT_FALSE(lcmio::validate(m).has_value());
  m.landmarks[0].type = 3;
  EXPECT_NE(lcmio::validate(m).value_or("").find("landmark 0: type 3"), std::string::npos);
  m.landmarks[0].type = 1;
  m.landmarks[0].kind = 7;
  EXPECT_NE(lcmio::validate(m).value_or("").find("landmark 0: unknown kind 7"), std::string::npos);
  m.landmarks[0].kind = feature_t::KIND_VERTICAL_LINE;
  m.landmarks[0].covariance[1][1] = -0.5;
  EXPECT_NE(lcmio::validate(m).value_or("").find("landmark 0: covariance has a negative variance"), std::string::npos);
  m.landmarks[0].covariance[1][1] = 0.5;
  EXPECT_FALSE(lcmio::validate(m).has_value());
  m.num_candidates = -1;
  EXPECT_EQ(lcmio::validate(m).value_or(""), "negative num_candidates -1");

  process_status_t st{};
  st.state = process_status_t::STATE_ERROR;
  EXPECT_FALSE(lcmio::validate(st).has_value());
  st.state = 9;
  EXPECT_NE(lcmio::validate(st).value_or("").find("unknown state 9"), std::string::npos);
  st.state = process_status_t::STATE_RUNNING;
  st.utime = -1;
  EXPECT_EQ(lcmio::validate(st).value_or(""), "negative utime -1");

  particles_t ps{};
  ps.num_particles = 2;
  ps.x_m = ps.y_m = ps.theta_rad = {0.0, 0.0};
  ps.weight = {1.0, 0.0};
  EXPECT_FALSE(lcmio::validate(ps).has_value());
  ps.weight = {1.5, -0.5};
  EXPECT_NE(lcmio::validate(ps).value_or("").find("particle 1: negative weight"), std::string::npos);
}

// A count its array does not hold (a message built in code, e.g. a producer checking its own
// output) made validate read past the array (ASan: heap-buffer-overflow in validate(particles_t)).
TEST(Validate, ACountThatItsArrayDoesNotHoldIsRefusedNotReadPast) {
  particles_t ps{};
  ps.num_particles = 3;
  ps.x_m = ps.y_m = ps.theta_rad = ps.weight = {0.0};
  EXPECT_EQ(lcmio::validate(ps).value_or(""), "num_particles 3 != its array's size 1");
  features_t f{};
  f.num_features = 2;
  EXPECT_EQ(lcmio::validate(f).value_or(""), "num_features 2 != its array's size 0");
  map_t m{};
  m.landmarks.resize(1);
  EXPECT_EQ(lcmio::validate(m).value_or(""), "num_landmarks 0 != its array's size 1");
  associations_t a{};
  a.num_features = 1;
  EXPECT_EQ(lcmio::validate(a).value_or(""), "num_features 1 != its array's size 0");
  feature_labels_t l{};
  l.num_features = 1;
  l.landmark_id = {3};
  EXPECT_EQ(lcmio::validate(l).value_or(""), "num_features 1 != its array's size 0");  // source_code
}

TEST(Validate, AssociationsLabelsAndTheLimitsAtTheirBounds) {
  const lcmio::Limits lim;
  // A utime near INT64_MAX (a corrupted field) overflowed a receiver's utime + window.
  odometry_t o{};
  o.utime = lcmio::kMaxUtime;
  EXPECT_FALSE(lcmio::validate(o).has_value());
  o.utime = lcmio::kMaxUtime + 1;
  EXPECT_EQ(lcmio::validate(o).value_or(""), "utime 4611686018427387905 beyond 2^62 us (a corrupted field)");
  o.utime = 1;
  o.seq = -1;
  EXPECT_EQ(lcmio::validate(o).value_or(""), "negative seq -1");

  associations_t a{};
  a.num_features = lim.max_features;
  a.landmark_id.assign(static_cast<size_t>(a.num_features), +associations_t::NOT_ASSOCIATED);
  EXPECT_FALSE(lcmio::validate(a).has_value());
  a.landmark_id[7] = -3;
  EXPECT_EQ(lcmio::validate(a).value_or(""), "feature 7: landmark_id -3 below -2");
  a.num_features = lim.max_features + 1;
  a.landmark_id.push_back(0);
  EXPECT_EQ(lcmio::validate(a).value_or(""), "num_features out of range");

  feature_labels_t l{};
  l.num_features = 2;
  l.landmark_id = {+feature_labels_t::UNKNOWN, 12};
  l.source_code = {9, 12};
  EXPECT_FALSE(lcmio::validate(l).has_value());
  l.landmark_id[0] = -3;
  EXPECT_EQ(lcmio::validate(l).value_or(""), "feature 0: landmark_id -3 below -2");
  l.landmark_id[0] = 1;
  l.features_seq = -1;
  EXPECT_EQ(lcmio::validate(l).value_or(""), "negative features_seq -1");
  l.features_seq = 0;
  l.seq = -1;
  EXPECT_EQ(lcmio::validate(l).value_or(""), "negative seq -1");

  map_t m{};
  m.num_landmarks = lim.max_landmarks + 1;
  m.landmarks.resize(static_cast<size_t>(m.num_landmarks));
  EXPECT_EQ(lcmio::validate(m).value_or(""), "num_landmarks out of range");
  particles_t ps{};
  ps.num_particles = lim.max_particles + 1;
  EXPECT_EQ(lcmio::validate(ps).value_or(""), "num_particles out of range");

  image_t im{};
  im.pixel_format = image_t::FORMAT_GRAY8;
  im.width = lim.max_image_side_px, im.height = 1, im.row_stride = im.width;
  im.data.assign(static_cast<size_t>(im.width), 0), im.size = im.width;
  EXPECT_FALSE(lcmio::validate(im).has_value());
  im.width = im.row_stride = lim.max_image_side_px + 1;
  im.data.resize(static_cast<size_t>(im.width)), im.size = im.width;
  EXPECT_NE(lcmio::validate(im).value_or("").find("image size"), std::string::npos);
  im.pixel_format = image_t::FORMAT_PNG, im.width = 4, im.row_stride = 0, im.size = 0, im.data.clear();
  EXPECT_EQ(lcmio::validate(im).value_or(""), "empty compressed image");
  im.size = 5;
  EXPECT_EQ(lcmio::validate(im).value_or(""), "image data size 5 invalid");

  features_t f{};
  f.num_features = 1;
  feature_t ft{};
  ft.kind = feature_t::KIND_VERTICAL_LINE;
  ft.covariance[0][0] = 0.0;
  f.features = {ft};
  EXPECT_EQ(lcmio::validate(f).value_or(""), "feature 0: azimuth variance must be > 0");
  f.features[0].covariance[0][0] = 1e-4;
  EXPECT_FALSE(lcmio::validate(f).has_value());
  f.features[0].kind = feature_t::KIND_CEILING_LIGHT, f.features[0].has_elevation = true;
  f.features[0].covariance[1][1] = 1e-4;
  f.features[0].elevation_rad = M_PI / 2 + 1e-6;
  EXPECT_EQ(lcmio::validate(f).value_or(""), "feature 0: elevation outside [-pi/2, pi/2]");
}

// SLAM_LOCALISATION (since 0.5): what the .lcm file says receivers refuse.
TEST(Validate, LocalisationStatesCountsAndHypotheses) {
  slam_localisation_t m{};
  m.state = slam_localisation_t::STATE_LOCALISED;
  m.num_hypotheses = 1, m.num_tracked = 1, m.num_frames = 4, m.num_reported = 1;
  m.x_m = {1.0}, m.y_m = {2.0}, m.theta_rad = {0.5};
  m.covariance = {std::vector<double>(9, 0.01)};
  m.relative_log_likelihood = {0.0};
  m.frames_explained = {3};
  m.travel_m = {0.6};
  EXPECT_FALSE(lcmio::validate(m));
  auto bad = [&](auto change, const std::string& expect) {
    slam_localisation_t b = m;
    change(b);
    const auto e = lcmio::validate(b);
    ASSERT_TRUE(e.has_value()) << expect;
    EXPECT_NE(e->find(expect), std::string::npos) << *e;
  };
  bad([](slam_localisation_t& b) { b.state = 4; }, "state 4");
  bad([](slam_localisation_t& b) { b.num_frames = -1; }, "negative count");
  bad([](slam_localisation_t& b) { b.num_tracked = 0; }, "num_reported above num_tracked");
  bad([](slam_localisation_t& b) { b.x_m.clear(); }, "num_reported");
  bad([](slam_localisation_t& b) { b.theta_rad[0] = std::nan(""); }, "pose not finite");
  bad([](slam_localisation_t& b) { b.covariance[0].pop_back(); }, "not 9");
  bad([](slam_localisation_t& b) { b.covariance[0][4] = INFINITY; }, "covariance not finite");
  bad([](slam_localisation_t& b) { b.relative_log_likelihood[0] = 0.5; }, "relative_log_likelihood");
  bad([](slam_localisation_t& b) { b.travel_m[0] = -1.0; }, "travel_m");
  bad([](slam_localisation_t& b) { b.utime = -1; }, "utime");
}

TEST(ImageMsg, RawAndLosslessRoundTripsAreExact) {
  cv::Mat grey(48, 64, CV_8UC1);
  cv::randu(grey, 0, 255);
  cv::Mat bgr(48, 64, CV_8UC3);
  cv::randu(bgr, 0, 255);
  for (int8_t fmt : {image_t::FORMAT_GRAY8, image_t::FORMAT_PNG}) {
    image_t m{};
    lcmio::encodeImage(grey, fmt, m);
    ASSERT_FALSE(lcmio::validate(m).has_value());
    const auto back = lcmio::decodeImage(m);
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(cv::norm(*back, grey, cv::NORM_INF), 0.0) << "format " << int(fmt);
  }
  for (int8_t fmt : {image_t::FORMAT_BGR8, image_t::FORMAT_RGB8, image_t::FORMAT_PNG}) {
    image_t m{};
    lcmio::encodeImage(bgr, fmt, m);
    const auto back = lcmio::decodeImage(m);
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(cv::norm(*back, bgr, cv::NORM_INF), 0.0) << "format " << int(fmt);
  }
  image_t j{};
  lcmio::encodeImage(grey, image_t::FORMAT_JPEG, j);
  const auto jb = lcmio::decodeImage(j);
  ASSERT_TRUE(jb.has_value());
  EXPECT_EQ(jb->size(), grey.size());
}

TEST(ImageMsg, CorruptCompressedImagesAreRefusedWithAReason) {
  image_t m{};
  m.width = 64, m.height = 48, m.pixel_format = image_t::FORMAT_PNG, m.data.assign(100, 7), m.size = 100;
  std::string why;
  EXPECT_FALSE(lcmio::decodeImage(m, &why).has_value());
  EXPECT_EQ(why, "not a PNG, JPEG, BMP or PGM/PPM/PBM image (unknown signature)");
  cv::Mat grey(48, 64, CV_8UC1, cv::Scalar(9));
  lcmio::encodeImage(grey, image_t::FORMAT_PNG, m);
  m.data.resize(m.data.size() / 2);  // a valid header, truncated image data
  EXPECT_FALSE(lcmio::decodeImage(m, &why).has_value());
  EXPECT_EQ(why.rfind("truncated PNG: ", 0), 0u) << why;
  lcmio::encodeImage(grey, image_t::FORMAT_PNG, m);
  m.width = 65;  // header lies about the size
  EXPECT_FALSE(lcmio::decodeImage(m, &why).has_value());
  EXPECT_EQ(why, "compressed image's own header says 64x48, the message's 65x48");
}

// CRC-32 of PNG chunks (ISO 3309), so that a doctored IHDR is otherwise a well-formed PNG.
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

// A small PNG whose IHDR says 60000 x 60000 made cv::imdecode throw (CV_IO_MAX_IMAGE_PIXELS) out
// of the LCM callback of omnislam-features and omnislam-viewer, which exited. It is refused from its
// header (beyond the contract's 8192 px), whether or not the message's own size agrees with the
// lie; JPEG's frame header likewise.
TEST(ImageMsg, AHeaderClaimingAHugeImageIsRefusedNotThrown) {
  cv::Mat grey(48, 64, CV_8UC1, cv::Scalar(9));
  image_t m{};
  lcmio::encodeImage(grey, image_t::FORMAT_PNG, m);
  putBigEndian(m.data, 16, 60000);
  putBigEndian(m.data, 20, 60000);
  putBigEndian(m.data, 29, crc32(m.data.data() + 12, 17));  // type + 13 bytes of IHDR data
  std::string why;
  EXPECT_FALSE(lcmio::decodeImage(m, &why).has_value());
  EXPECT_EQ(why, "60000x60000, 1 channel, 8-bit PNG: a side beyond the limit of 8192 px");
  m.width = m.height = 60000;  // a message that agrees with its image's lie never reaches OpenCV
  why.clear();
  EXPECT_NO_THROW(EXPECT_FALSE(lcmio::decodeImage(m, &why).has_value()));
  EXPECT_EQ(why, "60000x60000, 1 channel, 8-bit PNG: a side beyond the limit of 8192 px");

  image_t j{};
  lcmio::encodeImage(grey, image_t::FORMAT_JPEG, j);
  size_t sof = 2;  // find the SOF0 segment the encoder wrote
  while (sof + 9 < j.data.size() && !(j.data[sof] == 0xFF && j.data[sof + 1] == 0xC0)) ++sof;
  ASSERT_LT(sof + 9, j.data.size());
  j.data[sof + 5] = j.data[sof + 6] = 0xEA;  // height 60138
  EXPECT_FALSE(lcmio::decodeImage(j, &why).has_value());
  EXPECT_EQ(why, "64x60138, 1 channel, 8-bit JPEG: a side beyond the limit of 8192 px");
  j.data[sof + 5] = 0, j.data[sof + 6] = 49;  // height 49: within the limits, not the message's 48
  EXPECT_FALSE(lcmio::decodeImage(j, &why).has_value());
  EXPECT_EQ(why, "compressed image's own header says 64x49, the message's 64x48");
  image_t bad{};
  bad.width = 64, bad.height = 48, bad.pixel_format = image_t::FORMAT_JPEG, bad.data = {0xFF, 0xD8, 0xFF, 0xDA, 0, 2};
  EXPECT_FALSE(lcmio::decodeImage(bad, &why).has_value());
  EXPECT_EQ(why, "JPEG: marker 0xFFDA at byte 3 before any frame header");
}

// The decompression bomb of issue 46 (an 8192 x 8192 16-bit PNG of a few hundred kB: 128 MiB of
// pixels) is refused from its header, and so are a 16-bit image within the limits, a truncated
// JPEG (which OpenCV decodes anyway), data of the other codec, and what a consumer's own check
// refuses (its camera's size) before a pixel is allocated.
TEST(ImageMsg, HeadersAreCheckedBeforeAnyPixelIsDecoded) {
  cv::Mat grey(48, 64, CV_8UC1, cv::Scalar(9));
  image_t m{};
  lcmio::encodeImage(grey, image_t::FORMAT_PNG, m);
  auto doctor = [&](uint32_t w, uint32_t h, uint8_t depth) {
    putBigEndian(m.data, 16, w);
    putBigEndian(m.data, 20, h);
    m.data[24] = depth;
    putBigEndian(m.data, 29, crc32(m.data.data() + 12, 17));
    m.width = static_cast<int32_t>(w), m.height = static_cast<int32_t>(h);
  };
  doctor(8192, 8192, 16);
  std::string why;
  EXPECT_FALSE(lcmio::decodeImage(m, &why).has_value());
  EXPECT_EQ(why, "8192x8192, 1 channel, 16-bit PNG: would decode into 134217728 bytes, beyond the limit of 67108864");
  doctor(64, 48, 16);
  EXPECT_FALSE(lcmio::decodeImage(m, &why).has_value());
  EXPECT_EQ(why, "64x48, 1 channel, 16-bit PNG: OMNI_IMAGE carries 8-bit images");
  doctor(4096, 4096, 8);  // 16 MiB of pixels: within the limits; the consumer's camera is 64 x 48
  int checked = 0;
  const vision::HeaderCheck camera = [&](const vision::ImageHeader& h) -> std::optional<std::string> {
    ++checked;
    if (h.width_px != 64 || h.height_px != 48) return std::string("not the camera's size");
    return std::nullopt;
  };
  EXPECT_FALSE(lcmio::decodeImage(m, &why, camera).has_value());
  EXPECT_EQ(why, "not the camera's size");
  EXPECT_EQ(checked, 1);

  image_t j{};
  lcmio::encodeImage(grey, image_t::FORMAT_JPEG, j);
  j.data.resize(j.data.size() - 30);
  j.size = static_cast<int32_t>(j.data.size());
  EXPECT_FALSE(lcmio::decodeImage(j, &why).has_value());
  EXPECT_EQ(why.rfind("truncated JPEG: no end-of-image marker (EOI)", 0), 0u) << why;
  image_t p{};
  lcmio::encodeImage(grey, image_t::FORMAT_PNG, p);
  p.pixel_format = image_t::FORMAT_JPEG;
  EXPECT_FALSE(lcmio::decodeImage(p, &why).has_value());
  EXPECT_EQ(why, "pixel_format says JPEG, the data is a PNG");
  lcmio::encodeImage(grey, image_t::FORMAT_JPEG, j);
  const auto ok = lcmio::decodeImage(j, &why, camera);
  ASSERT_TRUE(ok.has_value()) << why;
  EXPECT_EQ(ok->size(), grey.size());
}

// Seeded corruptions of a PNG and a JPEG (bytes changed, headers included, and truncations):
// decodeImage never throws, and what it returns has the message's size.
TEST(ImageMsg, CorruptedCompressedImagesNeverThrow) {
  cv::Mat grey(48, 64, CV_8UC1);
  cv::randu(grey, 0, 255);
  std::mt19937 rng(20261124);
  for (int8_t fmt : {image_t::FORMAT_PNG, image_t::FORMAT_JPEG}) {
    image_t good{};
    lcmio::encodeImage(grey, fmt, good);
    int decoded = 0;
    for (int trial = 0; trial < 400; ++trial) {  // libpng prints a line for most
      image_t m = good;
      std::uniform_int_distribution<size_t> head(0, std::min<size_t>(m.data.size() - 1, 200));
      const int edits = 1 + trial % 4;
      for (int e = 0; e < edits; ++e) m.data[head(rng)] = static_cast<uint8_t>(rng());
      if (trial % 3 == 0) m.data.resize(std::uniform_int_distribution<size_t>(0, m.data.size())(rng));
      std::string why;
      std::optional<cv::Mat> img;
      ASSERT_NO_THROW(img = lcmio::decodeImage(m, &why)) << "format " << int(fmt) << ", trial " << trial;
      if (img) {
        ++decoded;
        EXPECT_EQ(img->cols, 64);
        EXPECT_EQ(img->rows, 48);
      } else {
        EXPECT_FALSE(why.empty());
      }
    }
    EXPECT_LT(decoded, 400) << "format " << int(fmt) << ": the corruptions must reach the refusals";
  }
}

}  // namespace
