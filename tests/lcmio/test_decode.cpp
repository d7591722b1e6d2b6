// lcmio::decode: lying array counts and string lengths are refused before lcm-gen's decode can
// throw or allocate for them, and seeded random corruptions of every type of the contract never
// throw; whatever they decode to re-encodes to a stable encoding.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

#include "omnislam/lcmio/decode.h"

using namespace omnislam;

namespace {

template <class Msg>
std::vector<uint8_t> encode(const Msg& m) {
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(b.data(), 0, static_cast<int>(b.size())), static_cast<int>(b.size()));
  return b;
}

void putI32(std::vector<uint8_t>& b, size_t at, int32_t v) {
  const auto u = static_cast<uint32_t>(v);
  const uint8_t be[4] = {uint8_t(u >> 24), uint8_t(u >> 16), uint8_t(u >> 8), uint8_t(u)};
  std::memcpy(&b[at], be, 4);
}

features_t sampleFeatures() {
  features_t m{};
  m.utime = 5, m.seq = 1, m.image_seq = 1, m.detector = "x";
  m.num_features = 2;
  m.features.resize(2);
  m.features[0].kind = feature_t::KIND_VERTICAL_LINE;
  m.features[1].kind = feature_t::KIND_CEILING_LIGHT, m.features[1].has_elevation = true;
  return m;
}
image_t sampleImage() {
  image_t m{};
  m.camera_name = "cam", m.width = 4, m.height = 2, m.row_stride = 4, m.size = 8;
  m.data.assign(8, 7);
  return m;
}
map_t sampleMap() {
  map_t m{};
  m.num_landmarks = 2;
  m.landmarks.resize(2);
  m.landmarks[1].id = 9;
  m.num_candidates = 3;
  return m;
}
particles_t sampleParticles() {
  particles_t m{};
  m.num_particles = 3;
  m.x_m = m.y_m = m.theta_rad = {1.0, 2.0, 3.0};
  m.weight = {0.2, 0.3, 0.5};
  return m;
}
associations_t sampleAssociations() {
  associations_t m{};
  m.num_features = 3;
  m.landmark_id = {4, -1, -2};
  return m;
}
feature_labels_t sampleLabels() {
  feature_labels_t m{};
  m.num_features = 2;
  m.landmark_id = {6, -1};
  m.source_code = {63, 14};
  return m;
}
process_status_t sampleStatus() {
  process_status_t m{};
  m.name = "slam", m.last_error = "", m.detail = "ok";
  return m;
}
pose_t samplePose() {
  pose_t m{};
  m.x_m = 1.0;
  return m;
}
slam_localisation_t sampleLocalisation() {
  slam_localisation_t m{};
  m.state = slam_localisation_t::STATE_AMBIGUOUS;
  m.num_hypotheses = m.num_tracked = m.num_reported = 2;
  m.x_m = {1.0, 5.0}, m.y_m = {2.0, 6.0}, m.theta_rad = {0.1, -3.0};
  m.covariance.assign(2, std::vector<double>(9, 0.0));
  m.relative_log_likelihood = {0.0, -1.5};
  m.frames_explained = {3, 3};
  m.travel_m = {0.5, 0.5};
  return m;
}
odometry_t sampleOdometry() {
  odometry_t m{};
  m.theta_rad = 0.5;
  return m;
}

/// Decodes bytes of an encoded sample with the count (or string length) at `at` replaced by v.
template <class Msg>
std::string refusal(const Msg& sample, size_t at, int32_t v) {
  std::vector<uint8_t> b = encode(sample);
  putI32(b, at, v);
  Msg out;
  return lcmio::decode(b.data(), b.size(), out).value_or("accepted");
}

TEST(Decode, ValidMessagesOfEveryTypeRoundTrip) {
  features_t f;
  const auto fb = encode(sampleFeatures());
  ASSERT_FALSE(lcmio::decode(fb.data(), fb.size(), f));
  EXPECT_EQ(f.num_features, 2);
  EXPECT_TRUE(f.features[1].has_elevation);
  image_t i;
  const auto ib = encode(sampleImage());
  ASSERT_FALSE(lcmio::decode(ib.data(), ib.size(), i));
  EXPECT_EQ(i.data, std::vector<uint8_t>(8, 7));
  process_status_t s;
  const auto sb = encode(sampleStatus());
  ASSERT_FALSE(lcmio::decode(sb.data(), sb.size(), s));
  EXPECT_EQ(s.detail, "ok");
  // The wrong type, a short buffer, and a trailing byte.
  EXPECT_EQ(lcmio::decode(fb.data(), fb.size(), i).value_or(""), "wrong type (fingerprint)");
  EXPECT_EQ(lcmio::decode(fb.data(), 5, f).value_or(""), "shorter than a fingerprint");
  std::vector<uint8_t> longer = fb;
  longer.push_back(0);
  EXPECT_EQ(lcmio::decode(longer.data(), longer.size(), f).value_or(""), "corrupt");
}

// Offsets below: 8 fingerprint bytes, then the fields in .lcm order (int64 8, string 4 + bytes + NUL).
TEST(Decode, LyingArrayCountsAreRefusedBeforeAnyAllocation) {
  const size_t features_count = 8 + 3 * 8 + (4 + 2) + 3 * 8;  // detector "x"
  for (int32_t v : {-1, 3, 20'000'000, 0x7fffffff}) {
    EXPECT_NE(refusal(sampleFeatures(), features_count, v).find("num_features " + std::to_string(v) + " outside 0..2"),
              std::string::npos)
        << v << ": " << refusal(sampleFeatures(), features_count, v);
  }
  EXPECT_EQ(refusal(sampleFeatures(), features_count, 1), "corrupt");  // fits, but bytes are left over
  const size_t image_size = 8 + 2 * 8 + (4 + 4) + 3 * 4 + 1;           // camera_name "cam"
  EXPECT_EQ(refusal(sampleImage(), image_size, -8), "size -8 outside 0..8 (what the 8 bytes left hold)");
  EXPECT_EQ(refusal(sampleImage(), image_size, 9), "size 9 outside 0..8 (what the 8 bytes left hold)");
  const size_t counted = 8 + 3 * 8;  // map, particles, associations, labels: utime, seq, *_seq
  EXPECT_NE(refusal(sampleMap(), counted, 3).find("num_landmarks 3 outside 0..2"), std::string::npos);
  EXPECT_NE(refusal(sampleParticles(), counted, -1).find("num_particles -1 outside 0..3"), std::string::npos);
  EXPECT_NE(refusal(sampleAssociations(), counted, 1 << 30).find("num_features 1073741824 outside 0..3"),
            std::string::npos);
  EXPECT_NE(refusal(sampleLabels(), counted, 3).find("num_features 3 outside 0..2"), std::string::npos);
  const size_t reported = 8 + 3 * 8 + 1 + 3 * 4;  // slam_localisation_t: utime, seq, input_seq, state, 3 counts
  EXPECT_NE(refusal(sampleLocalisation(), reported, 3).find("num_reported 3 outside 0..2"), std::string::npos);
  EXPECT_NE(refusal(sampleLocalisation(), reported, -1).find("num_reported -1 outside 0..2"), std::string::npos);
  slam_localisation_t l;
  const auto lb = encode(sampleLocalisation());
  ASSERT_FALSE(lcmio::decode(lb.data(), lb.size(), l));
  EXPECT_EQ(l.theta_rad, (std::vector<double>{0.1, -3.0}));
  EXPECT_EQ(l.covariance.size(), 2u);
}

TEST(Decode, LyingStringLengthsAreRefused) {
  const size_t name = 8 + 2 * 8;
  EXPECT_EQ(refusal(sampleStatus(), name, -5).substr(0, 25), "name length -5 outside 1.");
  EXPECT_EQ(refusal(sampleStatus(), name, 0).substr(0, 24), "name length 0 outside 1.");
  EXPECT_EQ(refusal(sampleStatus(), name, 1 << 30).substr(0, 32), "name length 1073741824 outside 1");
  const size_t detector = 8 + 3 * 8;
  EXPECT_EQ(refusal(sampleFeatures(), detector, -1).substr(0, 27), "detector length -1 outside ");
  const size_t camera_name = 8 + 2 * 8;
  EXPECT_EQ(refusal(sampleImage(), camera_name, 0x7fffffff).substr(0, 38), "camera_name length 2147483647 outside ");
  // A NUL inside, or none at the end: lcm-gen would decode it and then encode another length.
  std::vector<uint8_t> b = encode(sampleStatus());
  b[name + 4 + 1] = 0;  // "s\0am"
  process_status_t out;
  EXPECT_EQ(lcmio::decode(b.data(), b.size(), out).value_or(""), "name is not one NUL-terminated string");
  b = encode(sampleStatus());
  b[name + 4 + 4] = 'x';  // "slamx", no NUL
  EXPECT_EQ(lcmio::decode(b.data(), b.size(), out).value_or(""), "name is not one NUL-terminated string");
}

/// Seeded corruptions of a valid encoding: byte flips, extreme int32s at random places, truncation
/// and extension. decode must never throw; when it accepts, the message re-encodes to bytes that
/// decode and re-encode to themselves (booleans normalise on the first pass).
template <class Msg>
void fuzz(const Msg& sample, uint64_t seed, int rounds) {
  const std::vector<uint8_t> good = encode(sample);
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> op(0, 3), nmut(1, 4);
  int accepted = 0;
  for (int r = 0; r < rounds; ++r) {
    std::vector<uint8_t> b = good;
    const int k = nmut(rng);
    for (int j = 0; j < k && !b.empty(); ++j) {
      const size_t at = std::uniform_int_distribution<size_t>(0, b.size() - 1)(rng);
      switch (op(rng)) {
        case 0: b[at] ^= static_cast<uint8_t>(1u << (rng() % 8)); break;
        case 1:
          if (b.size() >= 4) {
            const int32_t extreme[] = {-1, 0, 1, 0x7fffffff, INT32_MIN, 20'000'000, static_cast<int32_t>(rng())};
            putI32(b, std::min(at, b.size() - 4), extreme[rng() % 7]);
          }
          break;
        case 2: b.resize(at); break;
        default: b.insert(b.begin() + static_cast<long>(at), static_cast<uint8_t>(rng())); break;
      }
    }
    if (r % 4 != 0 && b.size() >= 8) std::memcpy(b.data(), good.data(), 8);  // mostly keep the fingerprint
    Msg m;
    std::optional<std::string> why;
    ASSERT_NO_THROW(why = lcmio::decode(b.data(), b.size(), m)) << Msg::getTypeName() << " round " << r;
    // The length checks, not decode's last-resort catch, must be what refuses a lie.
    if (why) {
      ASSERT_NE(why->rfind("corrupt (", 0), 0u) << Msg::getTypeName() << " round " << r << ": " << *why;
      continue;
    }
    ++accepted;
    const std::vector<uint8_t> once = encode(m);
    Msg again;
    ASSERT_FALSE(lcmio::decode(once.data(), once.size(), again)) << Msg::getTypeName() << " round " << r;
    EXPECT_EQ(encode(again), once) << Msg::getTypeName() << " round " << r;
  }
  // Some corruptions keep a valid encoding (a flipped bit in a double): the check is not vacuous.
  EXPECT_GT(accepted, rounds / 20) << Msg::getTypeName();
}

TEST(Decode, SeededCorruptionsOfEveryTypeNeverThrow) {
  const int kRounds = 3000;
  fuzz(sampleFeatures(), 1, kRounds);
  fuzz(sampleImage(), 2, kRounds);
  fuzz(sampleMap(), 3, kRounds);
  fuzz(sampleParticles(), 4, kRounds);
  fuzz(sampleAssociations(), 5, kRounds);
  fuzz(sampleLabels(), 6, kRounds);
  fuzz(sampleStatus(), 7, kRounds);
  fuzz(samplePose(), 8, kRounds);
  fuzz(sampleOdometry(), 9, kRounds);
  fuzz(sampleLocalisation(), 10, kRounds);
}

}  // namespace
