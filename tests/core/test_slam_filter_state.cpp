// Checkpoints of the FastSLAM filter (FastSlam::saveState / loadState) and their envelope
// (byte_codec.h): a loaded filter is the saved one bit for bit (its state writes the same bytes) and
// its next steps give bit-identical results to the filter that was never saved, for several filter
// variants; a damaged, truncated, foreign or other-version buffer is refused with its reason, and
// no damaged buffer crashes the reader.
#include <gtest/gtest.h>

#include <array>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "omnislam/core/byte_codec.h"
#include "omnislam/core/slam/fastslam.h"

namespace {

using namespace omnislam;
using namespace omnislam::slam;

const Eigen::Vector3d kCam(0.0, 0.0, 1.8);
constexpr double kSigma = 0.3 * kPi / 180.0;
const StateMagic kMagic{'O', 'S', 'L', 'M', 'T', 'E', 'S', 'T'};

/// Frame k of a drive round a loop under 8 lights and beside 4 vertical lines (with colours), noisy.
std::vector<BearingMeasurement> frame(int k, Pose2* odom) {
  const double a = 0.05 * k;
  *odom = Pose2{6.0 * std::sin(a), 4.0 - 4.0 * std::cos(a), wrapAngle(a)};
  std::mt19937_64 rng(static_cast<std::uint64_t>(k) + 11);
  std::normal_distribution<double> n(0.0, kSigma);
  std::vector<BearingMeasurement> z;
  for (double x : {-4.0, 0.0, 4.0, 8.0})
    for (double y : {-1.0, 7.0}) {
      const auto p = predictMeasurement(LandmarkKind::kPoint3D, Eigen::Vector3d(x, y, 6.5), *odom, kCam);
      BearingMeasurement m;
      m.azimuth_rad = wrapAngle((*p)(0) + n(rng));
      m.elevation_rad = (*p)(1) + n(rng);
      m.cov_rad2 = Eigen::Matrix2d::Identity() * kSigma * kSigma;
      m.p_CinR_m = kCam;
      z.push_back(m);
    }
  for (const auto& [x, y] : {std::pair{-9.0, 3.0}, {12.0, 3.0}, {2.0, -6.0}, {2.0, 12.0}}) {
    const auto p = predictMeasurement(LandmarkKind::kVerticalLine, Eigen::Vector3d(x, y, 0.0), *odom, kCam);
    BearingMeasurement m;
    m.kind = LandmarkKind::kVerticalLine;
    m.azimuth_rad = wrapAngle((*p)(0) + n(rng));
    m.cov_rad2 = Eigen::Matrix2d::Identity() * kSigma * kSigma;
    m.p_CinR_m = kCam;
    m.descriptor.valid = true;
    for (std::size_t i = 0; i < 6; ++i) m.descriptor.rgb[i] = static_cast<float>(20.0 * i + x);
    z.push_back(m);
  }
  return z;
}

std::vector<std::uint8_t> stateOf(const FastSlam& f) {
  ByteWriter w;
  f.saveState(w);
  return w.release();
}

FastSlam load(const FastSlamOptions& o, const std::vector<std::uint8_t>& bytes) {
  ByteReader r(bytes);
  FastSlam f = FastSlam::loadState(o, r);
  r.expectEnd("filter state");
  return f;
}

/// A filter after `steps` frames (every fifth an odometry-only step).
FastSlam runFor(const FastSlamOptions& o, int steps, Pose2* odom_prev) {
  FastSlam f(o, 42);
  f.initialise(Pose2{}, {}, Eigen::Matrix3d::Identity() * 1e-4);
  *odom_prev = Pose2{};
  for (int k = 1; k <= steps; ++k) {
    Pose2 odom;
    const auto z = frame(k, &odom);
    if (k % 5 == 0) f.predictOnly(*odom_prev, odom);
    else f.step(*odom_prev, odom, z);
    *odom_prev = odom;
  }
  return f;
}

void expectSameStep(const StepResult& a, const StepResult& b, int k) {
  EXPECT_EQ(a.ess, b.ess) << k;
  EXPECT_EQ(a.resampled, b.resampled) << k;
  EXPECT_EQ(a.best_particle, b.best_particle) << k;
  EXPECT_EQ(a.landmark_of_measurement, b.landmark_of_measurement) << k;
  EXPECT_EQ(a.num_initialised, b.num_initialised) << k;
  EXPECT_EQ(a.num_landmarks, b.num_landmarks) << k;
  EXPECT_EQ(a.num_candidates, b.num_candidates) << k;
}

/// Distinct maps, cells and candidates held by the particles (what sharing saves).
std::array<std::size_t, 3> sharedStorage(const FastSlam& f) {
  std::set<const void*> maps, cells, cands;
  for (const Particle& p : f.particles()) {
    maps.insert(p.map.rootNode());
    for (const auto& kc : p.map.cells()) cells.insert(kc.second.get());
    for (const auto& c : p.candidates) cands.insert(c.get());
  }
  return {maps.size(), cells.size(), cands.size()};
}

struct Variant {
  const char* name;
  FastSlamOptions options;
};

std::vector<Variant> variants() {
  std::vector<Variant> v;
  FastSlamOptions base;
  base.num_particles = 12;
  v.push_back({"fastslam2_hungarian", base});
  FastSlamOptions fs1 = base;
  fs1.proposal = FastSlam1Proposal{};
  fs1.perception.detection_probability = 0.9;
  v.push_back({"fastslam1_hungarian", fs1});
  FastSlamOptions kept = base;  // log weights carried between steps, scale anchoring
  kept.resample_ess_fraction = 0.5;
  kept.odometry_scale_correction = true;
  kept.association = AssociationMethod::kMaximumLikelihood;
  v.push_back({"ess_resampling_scale_ml", kept});
  return v;
}

TEST(FilterState, LoadedFilterIsTheSavedOneAndContinuesBitForBit) {
  for (const Variant& var : variants()) {
    SCOPED_TRACE(var.name);
    Pose2 odom_prev;
    FastSlam a = runFor(var.options, 40, &odom_prev);
    ASSERT_GT(a.bestParticle().map.size(), 0u) << "the scenario must have made landmarks";
    const std::vector<std::uint8_t> saved = stateOf(a);
    FastSlam b = load(var.options, saved);
    EXPECT_EQ(stateOf(b), saved) << "the loaded filter writes the same state";
    // Results as published, and the storage shared as before (maps and candidates not multiplied).
    EXPECT_EQ(b.meanPose().vec(), a.meanPose().vec());
    EXPECT_EQ(b.poseCovariance(), a.poseCovariance());
    EXPECT_EQ(b.ess(), a.ess());
    EXPECT_EQ(sharedStorage(b), sharedStorage(a));
    const auto ma = a.bestMap(), mb = b.bestMap();
    ASSERT_EQ(ma.size(), mb.size());
    for (std::size_t i = 0; i < ma.size(); ++i) {
      EXPECT_EQ(ma[i].id, mb[i].id);
      EXPECT_EQ(ma[i].p_LinW_m, mb[i].p_LinW_m);
      EXPECT_EQ(ma[i].cov_LinW_m2, mb[i].cov_LinW_m2);
      EXPECT_EQ(ma[i].counter, mb[i].counter);
      EXPECT_EQ(ma[i].type, mb[i].type);
    }
    // The next 60 steps (odometry-only ones among them) of both: identical, state and all.
    for (int k = 41; k <= 100; ++k) {
      Pose2 odom;
      const auto z = frame(k, &odom);
      if (k % 5 == 0) {
        a.predictOnly(odom_prev, odom);
        b.predictOnly(odom_prev, odom);
      } else {
        expectSameStep(a.step(odom_prev, odom, z), b.step(odom_prev, odom, z), k);
      }
      odom_prev = odom;
      ASSERT_EQ(stateOf(a), stateOf(b)) << "step " << k;
    }
    EXPECT_GT(a.bestParticle().map.size(), 4u);
  }
}

TEST(FilterState, FreshFilterAndPriorMapRoundTrip) {
  FastSlamOptions o;
  FastSlam f(o, 3);
  Landmark prior;
  prior.id = 7;
  prior.p_LinW_m = Eigen::Vector3d(1, 2, 6);
  prior.cov_LinW_m2 = Eigen::Matrix3d::Identity() * 0.01;
  f.initialise(Pose2{1, 2, 0.5}, {prior});
  const auto s = stateOf(f);
  FastSlam g = load(o, s);
  EXPECT_EQ(stateOf(g), s);
  Pose2 odom;
  const auto z = frame(1, &odom);
  expectSameStep(f.step(Pose2{}, odom, z), g.step(Pose2{}, odom, z), 1);
  EXPECT_EQ(stateOf(f), stateOf(g));
  // New ids continue after the prior map's in both.
  EXPECT_EQ(f.bestMap().front().id, 7u);
}

TEST(FilterState, OtherOptionsAreRefusedNamingTheKey) {
  FastSlamOptions o;
  o.num_particles = 12;
  Pose2 odom_prev;
  const auto s = stateOf(runFor(o, 10, &odom_prev));
  FastSlamOptions more = o;
  more.num_particles = 50;
  try {
    load(more, s);
    FAIL() << "a state of 12 particles loaded with 50";
  } catch (const StateFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("filter.particles = 12"), std::string::npos) << e.what();
  }
  FastSlamOptions loc = o;
  loc.update_map = false;
  EXPECT_THROW(load(loc, s), StateFormatError);
  FastSlamOptions cell = o;
  cell.map_cell_size_m = 2.0;
  EXPECT_THROW(load(cell, s), StateFormatError);
}

std::string reasonOf(const std::vector<std::uint8_t>& b, std::uint32_t version = 1) {
  try {
    openState(kMagic, version, b.data(), b.size());
  } catch (const StateFormatError& e) {
    return e.what();
  }
  return "";
}

TEST(StateEnvelope, RoundTripAndEveryDamageRefusedWithItsReason) {
  FastSlamOptions o;
  Pose2 odom_prev;
  const auto payload = stateOf(runFor(o, 30, &odom_prev));
  const auto sealed = sealState(kMagic, 1, payload);
  const OpenedState opened = openState(kMagic, 1, sealed.data(), sealed.size());
  EXPECT_EQ(opened.version, 1u);
  EXPECT_EQ(opened.payload, payload);

  // Every single flipped bit, at a spread of positions (the header, the payload, the checksum).
  for (std::size_t i = 0; i < sealed.size(); i += 1 + sealed.size() / 500) {
    auto b = sealed;
    b[i] ^= 0x10;
    const std::string why = reasonOf(b);
    EXPECT_FALSE(why.empty()) << "a flipped bit at byte " << i << " was not noticed";
    if (i >= 20) {
      EXPECT_NE(why.find("checksum mismatch"), std::string::npos) << i << ": " << why;
    }
  }
  // Truncated anywhere, also inside the header.
  for (std::size_t n :
       {std::size_t{0}, std::size_t{7}, std::size_t{19}, std::size_t{23}, sealed.size() / 2, sealed.size() - 1}) {
    const std::vector<std::uint8_t> b(sealed.begin(), sealed.begin() + static_cast<long>(n));
    EXPECT_NE(reasonOf(b).find("truncated"), std::string::npos) << n << ": " << reasonOf(b);
  }
  auto longer = sealed;
  longer.push_back(0);
  EXPECT_NE(reasonOf(longer).find("trailing bytes"), std::string::npos) << reasonOf(longer);
  EXPECT_NE(reasonOf(sealState(StateMagic{'N', 'O', 'T', 'M', 'I', 'N', 'E', '!'}, 1, payload)).find("wrong magic"),
            std::string::npos);
  EXPECT_NE(reasonOf(sealState(kMagic, 2, payload)).find("format version 2, this program reads version 1"),
            std::string::npos)
      << reasonOf(sealState(kMagic, 2, payload));
}

TEST(FilterState, DamagedPayloadNeverCrashesTheReader) {
  // Behind a good checksum the payload is trusted to be well formed; still, a reader given a
  // truncated or damaged one must throw its reason (or load numbers), never crash or allocate wildly.
  FastSlamOptions o;
  o.num_particles = 5;
  Pose2 odom_prev;
  const auto payload = stateOf(runFor(o, 25, &odom_prev));
  int refused = 0;
  for (std::size_t n = 0; n < payload.size(); n += 1 + payload.size() / 400) {
    const std::vector<std::uint8_t> b(payload.begin(), payload.begin() + static_cast<long>(n));
    ByteReader r(b);
    EXPECT_THROW(FastSlam::loadState(o, r), StateFormatError) << "truncated at " << n;
    ++refused;
  }
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 300; ++trial) {
    auto b = payload;
    b[rng() % b.size()] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
    ByteReader r(b);
    try {
      FastSlam::loadState(o, r);
    } catch (const StateFormatError&) {
      ++refused;
    }
  }
  EXPECT_GT(refused, 400);
}

}  // namespace
