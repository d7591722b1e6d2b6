// Lost and found in the step driver (lost.policy relocalise; lost_monitor.h, global_start.h): the
// robot tracking in a loaded map is carried elsewhere (a kidnap the odometry does not see); the
// driver reports STATE_LOST, publishes no pose until the global localiser's new fix, resumes near the
// truth, and the map is the same bytes before and after; without a kidnap, or with keep_tracking,
// the outputs are those of a driver without the policy.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>

#include "omnislam/core/angles.h"
#include "omnislam/core/slam/landmark_codec.h"
#include "omnislam/lcmio/validate.h"
#include "omnislam/runtime/checkpoint.h"
#include "omnislam/runtime/slam_driver.h"
#include "slam_inputs.h"

using namespace omnislam;
using namespace omnislam::runtime;
using namespace omnislam::testing;

namespace {

std::vector<std::uint8_t> bytesOf(const std::vector<slam::Landmark>& map) {
  ByteWriter w;
  for (const slam::Landmark& l : map) slam::putLandmark(w, l);
  return w.buffer();
}

/// The odometry frame O is not the map frame W: the odometry reports kWinO * (the drive's pose).
const Pose2 kWinO{-3.0, 7.0, 1.0};
constexpr int64_t kSecond = 1'000'000;

/// The hall drive (straight along +x at 0.27 m/s) in which, at kidnap_s, the robot is carried to
/// (7, 0.5) heading +y and drives on from there: the truth jumps, the odometry does not.
struct Kidnap {
  double at_s = 1e9;  ///< never by default
  Pose2 to_W{7.0, 0.5, kPi / 2};
  Pose2 truthAt(int64_t utime) const {
    const int64_t at = kT0 + static_cast<int64_t>(at_s * kSecond);
    if (utime < at) return hallTruthAt(utime);
    const Pose2 carry = to_W.compose(hallTruthAt(at).inverse());  // left-multiplied: motions unchanged
    return carry.compose(hallTruthAt(utime));
  }
};

SlamProcessOptions localiseFrom(slam::LostPolicy policy, bool localisation_only = true) {
  SlamProcessOptions o;
  o.start_source = SlamProcessOptions::StartSource::kFixed;
  o.start_pose_W = hallTruthAt(kT0);  // the first frame's pose
  o.load_map_path = "map.yaml";       // read by the process, not by the driver: the map is given to it
  o.localisation_only = localisation_only;
  o.lost.policy = policy;
  return o;
}

/// Everything one drive produced, with the map the driver holds after each frame.
struct DriveRun {
  std::vector<FrameOutput> outputs;
  std::vector<slam_localisation_t> localisation;
  std::vector<std::string> notes;
  std::optional<std::vector<std::uint8_t>> map_before_kidnap;  ///< the filter's, at the last frame before it
  std::vector<std::vector<std::uint8_t>> maps_while_lost;      ///< the map to be saved, at each lost frame
  std::optional<std::vector<std::uint8_t>> map_at_fix;         ///< the new filter's, when it starts
};

DriveRun drive(SlamDriver& d, int seconds, const Kidnap& k, const std::vector<Eigen::Vector3d>& lights) {
  DriveRun run;
  int64_t oseq = 0, fseq = 0;
  const auto take = [&](DriverResult r) {
    for (auto& o : r.outputs) run.outputs.push_back(std::move(o));
    for (auto& l : r.localisation) run.localisation.push_back(std::move(l));
    for (auto& n : r.notes) run.notes.push_back(std::move(n));
  };
  for (int64_t t = kT0; t <= kT0 + seconds * kSecond; t += 20'000) {
    take(d.onOdometry(odometryAt(t, oseq++, kWinO.compose(hallTruthAt(t)), 0.27)));
    const int64_t tf = t - 100'000;
    if (tf < kT0 || (tf - kT0) % kSecond != 0) continue;
    const bool before = tf < kT0 + static_cast<int64_t>(k.at_s * kSecond);
    const bool was_lost = !run.localisation.empty() && d.filter() == nullptr;
    take(d.onFeatures(lightFeatures(tf, fseq++, k.truthAt(tf), lights)));
    if (before && d.filter()) run.map_before_kidnap = bytesOf(d.filter()->bestMap());
    if (!d.filter() && d.filterToSave(nullptr))
      run.maps_while_lost.push_back(bytesOf(d.filterToSave(nullptr)->bestMap()));
    if (was_lost && d.filter() && !run.map_at_fix) run.map_at_fix = bytesOf(d.filter()->bestMap());
  }
  return run;
}

double headingErrorDeg(double a_rad, double b_rad) { return std::abs(wrapAngle(a_rad - b_rad)) * 180.0 / kPi; }

/// Checks the kidnapped run: LOST after the kidnap, no pose while lost, a fix within 5 m of travel
/// near the truth, tracking near the truth after it, the map the same bytes.
void expectLostAndFound(const DriveRun& run, const Kidnap& k) {
  const int64_t kidnap_utime = kT0 + static_cast<int64_t>(k.at_s * kSecond);
  ASSERT_GE(run.localisation.size(), 2u);
  const slam_localisation_t& lost = run.localisation.front();
  ASSERT_EQ(lost.state, slam_localisation_t::STATE_LOST);
  EXPECT_GE(lost.utime, kidnap_utime);
  EXPECT_LE(lost.utime, kidnap_utime + 5 * kSecond) << "lost within 5 frames of the kidnap";
  EXPECT_EQ(lost.num_reported, 0);
  const slam_localisation_t& fix = run.localisation.back();
  ASSERT_EQ(fix.state, slam_localisation_t::STATE_LOCALISED) << "not localised again";
  EXPECT_LE(0.27 * static_cast<double>(fix.utime - kidnap_utime) * 1e-6, 5.0) << "more than 5 m of travel";
  const Pose2 at_fix = k.truthAt(fix.utime);
  EXPECT_LT(std::hypot(fix.x_m[0] - at_fix.x_m, fix.y_m[0] - at_fix.y_m), 0.3);
  EXPECT_LT(headingErrorDeg(fix.theta_rad[0], at_fix.theta_rad), 2.0);
  for (std::size_t i = 0; i < run.localisation.size(); ++i) {
    EXPECT_FALSE(lcmio::validate(run.localisation[i]));
    EXPECT_EQ(run.localisation[i].seq, static_cast<int64_t>(i));
    if (i > 0 && i + 1 < run.localisation.size()) {
      EXPECT_NE(run.localisation[i].state, slam_localisation_t::STATE_LOCALISED) << "one fix only";
    }
  }
  int64_t pose_seq = 0;
  for (const FrameOutput& out : run.outputs) {
    EXPECT_EQ(out.pose.seq, pose_seq++) << "no gap in SLAM_POSE's sequence numbers";
    EXPECT_FALSE(out.pose.utime >= lost.utime && out.pose.utime <= fix.utime) << "a pose while lost";
    if (out.pose.utime >= kidnap_utime && out.pose.utime < lost.utime) continue;  // not seen yet
    const Pose2 truth = k.truthAt(out.pose.utime);
    EXPECT_LT(std::hypot(out.pose.x_m - truth.x_m, out.pose.y_m - truth.y_m), 0.3) << out.pose.input_seq;
    EXPECT_LT(headingErrorDeg(out.pose.theta_rad, truth.theta_rad), 2.0) << out.pose.input_seq;
  }
  ASSERT_TRUE(run.map_before_kidnap && run.map_at_fix);
  EXPECT_EQ(*run.map_at_fix, *run.map_before_kidnap) << "the map the filter starts from after the fix";
  ASSERT_FALSE(run.maps_while_lost.empty());
  for (const auto& m : run.maps_while_lost) EXPECT_EQ(m, *run.map_before_kidnap) << "the map while lost";
}

}  // namespace

// Localisation only (the map fixed), carried 5 m and turned a quarter at 15 s.
TEST(LostAndFound, KidnappedInLocalisationModeIsLostThenFoundInTheSameMap) {
  const auto lights = hallLightsPlus17th(true);
  Kidnap k;
  k.at_s = 15.0;
  SlamDriver d(localiseFrom(slam::LostPolicy::kRelocalise), exactMapOf(lights));
  const DriveRun run = drive(d, 45, k, lights);
  expectLostAndFound(run, k);
  EXPECT_EQ(*run.map_before_kidnap, bytesOf(exactMapOf(lights))) << "the loaded map, fixed";
  EXPECT_EQ(d.stats().lost, 1);
  EXPECT_EQ(d.stats().health_diverged, 0) << "the count test, not the health monitor, saw the kidnap";
  EXPECT_EQ(d.stats().localisation_fixes, 1);
  EXPECT_NE(d.summary().find("; lost 1"), std::string::npos) << d.summary();
  bool noted = false;
  for (const auto& n : run.notes) noted = noted || n.find("lost at frame seq") != std::string::npos;
  EXPECT_TRUE(noted);
}

// SLAM with a loaded map (the map grows): the frames between the kidnap and the verdict do not stay
// in the map; the new filter starts from the map as it was before the kidnap.
TEST(LostAndFound, KidnappedInSlamWithALoadedMapKeepsTheMapOfBeforeTheKidnap) {
  const auto lights = hallLightsPlus17th(true);
  Kidnap k;
  k.at_s = 15.0;
  SlamDriver d(localiseFrom(slam::LostPolicy::kRelocalise, false), exactMapOf(lights));
  const DriveRun run = drive(d, 45, k, lights);
  expectLostAndFound(run, k);
  EXPECT_EQ(d.stats().lost, 1);
}

// Nothing changes unless the robot is lost: the same drive without a kidnap gives the same bytes
// with relocalise as with keep_tracking, and no SLAM_LOCALISATION.
TEST(LostAndFound, WithoutAKidnapTheOutputsAreThoseOfKeepTracking) {
  const auto lights = hallLightsPlus17th(true);
  for (bool localisation_only : {true, false}) {
    SlamDriver a(localiseFrom(slam::LostPolicy::kRelocalise, localisation_only), exactMapOf(lights));
    SlamDriver b(localiseFrom(slam::LostPolicy::kKeepTracking, localisation_only), exactMapOf(lights));
    const DriveRun ra = drive(a, 40, Kidnap{}, lights), rb = drive(b, 40, Kidnap{}, lights);
    EXPECT_TRUE(ra.localisation.empty());
    EXPECT_EQ(a.stats().lost, 0);
    ASSERT_EQ(ra.outputs.size(), rb.outputs.size());
    for (std::size_t i = 0; i < ra.outputs.size(); ++i) {
      EXPECT_EQ(encoded(ra.outputs[i].pose), encoded(rb.outputs[i].pose));
      ASSERT_EQ(ra.outputs[i].map.has_value(), rb.outputs[i].map.has_value());
      if (ra.outputs[i].map) {
        EXPECT_EQ(encoded(*ra.outputs[i].map), encoded(*rb.outputs[i].map));
      }
    }
  }
}

// keep_tracking (the default): the kidnapped filter goes on; no SLAM_LOCALISATION at all.
TEST(LostAndFound, KeepTrackingNeverReportsLost) {
  const auto lights = hallLightsPlus17th(true);
  Kidnap k;
  k.at_s = 15.0;
  EXPECT_EQ(SlamProcessOptions{}.lost.policy, slam::LostPolicy::kKeepTracking);
  SlamDriver d(localiseFrom(slam::LostPolicy::kKeepTracking), exactMapOf(lights));
  const DriveRun run = drive(d, 30, k, lights);
  EXPECT_TRUE(run.localisation.empty());
  EXPECT_EQ(run.outputs.size(), 30u);
  EXPECT_EQ(d.stats().lost, 0);
}

/// The kidnapped drive's input messages (as drive() feeds them).
std::vector<InputMessage> kidnapStream(int seconds, const Kidnap& k, const std::vector<Eigen::Vector3d>& lights) {
  std::vector<InputMessage> v;
  int64_t oseq = 0, fseq = 0;
  for (int64_t t = kT0; t <= kT0 + seconds * kSecond; t += 20'000) {
    v.emplace_back(odometryAt(t, oseq++, kWinO.compose(hallTruthAt(t)), 0.27));
    const int64_t tf = t - 100'000;
    if (tf >= kT0 && (tf - kT0) % kSecond == 0) v.emplace_back(lightFeatures(tf, fseq++, k.truthAt(tf), lights));
  }
  return v;
}

/// Every output of a driver result, encoded: the frames' outputs, then SLAM_LOCALISATION.
void append(const DriverResult& r, std::vector<std::vector<uint8_t>>& out) {
  for (const FrameOutput& o : r.outputs) {
    out.push_back(encoded(o.pose));
    if (o.map) out.push_back(encoded(*o.map));
    if (o.health) out.push_back(encoded(*o.health));
  }
  for (const slam_localisation_t& l : r.localisation) out.push_back(encoded(l));
}

// A checkpoint written before the kidnap, between it and the verdict, and after the fix resumes to
// exactly the outputs of the run that was not interrupted (SLAM with a loaded map: the kept map is
// in the checkpoint). While lost none is written (the localiser's hypotheses are not in one).
TEST(LostAndFound, CheckpointsResumeBitForBitAroundTheKidnap) {
  const auto lights = hallLightsPlus17th(true);
  Kidnap k;
  k.at_s = 15.0;
  const auto msgs = kidnapStream(30, k, lights);
  const SlamProcessOptions opt = localiseFrom(slam::LostPolicy::kRelocalise, false);
  SlamDriver ref(opt, exactMapOf(lights));
  std::vector<std::vector<uint8_t>> ref_out;
  std::vector<std::size_t> outputs_before;
  for (const InputMessage& m : msgs) {
    outputs_before.push_back(ref_out.size());
    append(feedDriver(ref, m), ref_out);
  }
  ASSERT_EQ(ref.stats().lost, 1);
  for (int frame : {10, 16, 25}) {  // kidnapped at frame 15, lost at 17, found at 20
    SCOPED_TRACE("checkpoint after frame " + std::to_string(frame));
    std::size_t cut = 0;
    while (cut < msgs.size() &&
           !(std::holds_alternative<features_t>(msgs[cut]) && std::get<features_t>(msgs[cut]).seq == frame))
      ++cut;
    ++cut;  // after that frame
    SlamDriver before(opt, exactMapOf(lights));
    InputClock clock(opt.pairing.restart_jump_us);
    for (std::size_t i = 0; i < cut; ++i) {
      feedDriver(before, msgs[i]);
      const auto* f = std::get_if<features_t>(&msgs[i]);
      if (f) {
        EXPECT_EQ(before.relocalising(), f->seq >= 17 && f->seq < 20) << f->seq;
      }
    }
    const auto file = encodeCheckpoint(opt, before, clock, ReplayPosition{});
    SlamDriver after(opt, exactMapOf(lights));
    InputClock clock2(opt.pairing.restart_jump_us);
    decodeCheckpoint(file, opt, after, clock2);
    EXPECT_EQ(after.summary(), before.summary());
    std::vector<std::vector<uint8_t>> out;
    for (std::size_t i = cut; i < msgs.size(); ++i) append(feedDriver(after, msgs[i]), out);
    const std::vector<std::vector<uint8_t>> tail(ref_out.begin() + static_cast<long>(outputs_before[cut]),
                                                 ref_out.end());
    EXPECT_TRUE(out == tail) << "outputs after the resume differ from the uninterrupted run's";
    EXPECT_EQ(after.summary(), ref.summary());
  }
}

TEST(LostAndFound, SameInputsGiveIdenticalBytes) {
  const auto lights = hallLightsPlus17th(true);
  Kidnap k;
  k.at_s = 15.0;
  SlamDriver a(localiseFrom(slam::LostPolicy::kRelocalise), exactMapOf(lights));
  SlamDriver b(localiseFrom(slam::LostPolicy::kRelocalise), exactMapOf(lights));
  const DriveRun ra = drive(a, 40, k, lights), rb = drive(b, 40, k, lights);
  ASSERT_EQ(ra.localisation.size(), rb.localisation.size());
  for (std::size_t i = 0; i < ra.localisation.size(); ++i)
    EXPECT_EQ(encoded(ra.localisation[i]), encoded(rb.localisation[i]));
  ASSERT_EQ(ra.outputs.size(), rb.outputs.size());
  for (std::size_t i = 0; i < ra.outputs.size(); ++i)
    EXPECT_EQ(encoded(ra.outputs[i].pose), encoded(rb.outputs[i].pose));
}

// A map without lights cannot be localised in again: refused at start, naming the policy.
TEST(LostAndFound, RelocaliseNeedsLightsInTheMap) {
  std::vector<slam::Landmark> lines = exactMapOf(hallLightsPlus17th(true));
  for (auto& l : lines) l.kind = slam::LandmarkKind::kVerticalLine;
  try {
    SlamDriver d(localiseFrom(slam::LostPolicy::kRelocalise), lines);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("lost.policy relocalise"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(SlamDriver(localiseFrom(slam::LostPolicy::kKeepTracking), lines));
}
