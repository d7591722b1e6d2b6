// Keyframes in the SLAM runtime (filter.keyframes): at 10 Hz the filter steps once per 0.2 m, every
// frame is still answered, the frames between keyframes carry the estimate moved by the odometry and
// use no measurement, and with the criteria off every frame steps.
#include <gtest/gtest.h>

#include <cmath>

#include "omnislam/core/angles.h"
#include "omnislam/runtime/slam_driver.h"

using namespace omnislam;
using namespace omnislam::runtime;

namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;
constexpr double kSpeed_mps = 0.27;

/// Straight along x from (6, -3.25); standing still from 20 s on.
Pose2 truthAt(int64_t utime) {
  const double t = std::min(static_cast<double>(utime - kT0) * 1e-6, 20.0);
  return Pose2{6.0 + kSpeed_mps * t, -3.25, 0.0};
}

features_t frameAt(int64_t utime, int64_t seq) {
  features_t m{};
  m.utime = utime;
  m.seq = m.image_seq = seq;
  m.detector = "test";
  m.camera_position_m[2] = 1.8;
  const Pose2 x = truthAt(utime);
  for (double lx : {4.5, 13.5, 22.5})
    for (double ly : {-5.5, -1.0, 3.5}) {
      const Eigen::Vector3d d_W(lx - x.x_m, ly - x.y_m, 6.5 - 1.8);
      feature_t f{};
      f.kind = feature_t::KIND_CEILING_LIGHT;
      f.azimuth_rad = wrapAngle(std::atan2(d_W.y(), d_W.x()) - x.theta_rad);
      f.elevation_rad = std::atan2(d_W.z(), d_W.head<2>().norm());
      f.has_elevation = true;
      f.covariance[0][0] = f.covariance[1][1] = 2.7e-5;
      m.features.push_back(f);
    }
  m.num_features = static_cast<int32_t>(m.features.size());
  return m;
}

/// `seconds` of 50 Hz odometry and frames at `rate_hz`, each frame arriving 100 ms late.
std::vector<FrameOutput> run(SlamDriver& d, int seconds, int rate_hz) {
  std::vector<FrameOutput> outs;
  const int64_t period_us = 1'000'000 / rate_hz;
  int64_t oseq = 0, fseq = 0;
  for (int64_t t = kT0; t <= kT0 + seconds * 1'000'000LL; t += 20'000) {
    const Pose2 p = truthAt(t);
    odometry_t o{};
    o.utime = t, o.seq = oseq++, o.x_m = p.x_m, o.y_m = p.y_m, o.theta_rad = p.theta_rad;
    for (auto& out : d.onOdometry(o).outputs) outs.push_back(std::move(out));
    const int64_t frame_t = t - 100'000;
    if (frame_t >= kT0 && (frame_t - kT0) % period_us == 0)
      for (auto& out : d.onFeatures(frameAt(frame_t, fseq++)).outputs) outs.push_back(std::move(out));
  }
  return outs;
}

SlamProcessOptions keyframed() {
  SlamProcessOptions o;
  o.filter.keyframes.min_travel_m = 0.2;
  o.filter.keyframes.min_rotation_rad = deg2rad(5.0);
  o.filter.keyframes.max_interval_s = 1.0;
  return o;
}

}  // namespace

TEST(Keyframes, TenHertzStepsOncePerTravelAndAnswersEveryFrame) {
  SlamDriver d(keyframed());
  const auto outs = run(d, 19, 10);
  ASSERT_EQ(outs.size(), 190u);  // frames at 0 .. 18.9 s
  // 0.27 m/s: 0.2 m takes 8 frames (0.216 m), so the filter steps on frames 0, 8, 16, ...
  EXPECT_EQ(d.stats().frames_processed, 24);
  EXPECT_EQ(d.stats().frames_between_keyframes, 190 - 24);
  for (std::size_t i = 0; i < outs.size(); ++i) {
    const FrameOutput& f = outs[i];
    const bool keyframe = i % 8 == 0;
    EXPECT_EQ(f.pose.input_seq, static_cast<int64_t>(i));
    EXPECT_EQ(f.map.has_value(), keyframe) << i;
    ASSERT_TRUE(f.associations.has_value());
    int used = 0;
    for (int64_t id : f.associations->landmark_id) used += id != associations_t::NOT_USED;
    if (!keyframe) {
      EXPECT_EQ(used, 0) << "frame " << i << " between keyframes uses no measurement";
    }
    // Between keyframes: the last step's mean pose moved by the odometry since that step.
    const FrameOutput& k = outs[i - i % 8];
    const Pose2 expected =
        Pose2{k.pose.x_m, k.pose.y_m, k.pose.theta_rad}.compose(truthAt(k.pose.utime).between(truthAt(f.pose.utime)));
    EXPECT_NEAR(f.pose.x_m, expected.x_m, 1e-9) << i;
    EXPECT_NEAR(f.pose.y_m, expected.y_m, 1e-9) << i;
    EXPECT_NEAR(f.pose.theta_rad, expected.theta_rad, 1e-12) << i;
    // Exact odometry and bearings: every published pose follows the truth.
    const Pose2 truth = truthAt(f.pose.utime);
    EXPECT_LT(std::hypot(f.pose.x_m - truth.x_m, f.pose.y_m - truth.y_m), 0.1) << i;
  }
  // The pose of a frame between keyframes is the last step's moved by the odometry: its covariance
  // has grown by the motion noise of that travel.
  EXPECT_GT(outs[7].pose.covariance[0][0], outs[0].pose.covariance[0][0]);
}

TEST(Keyframes, AStandingRobotStepsOncePerInterval) {
  SlamDriver d(keyframed());
  run(d, 30, 10);  // moves 0-20 s, then stands for 10 s: one step per second, not per frame
  const int64_t moving = 20 * 10 / 8 + 1, standing = 10;
  EXPECT_NEAR(static_cast<double>(d.stats().frames_processed), static_cast<double>(moving + standing), 2.0);
}

TEST(Keyframes, WithTheCriteriaOffEveryFrameSteps) {
  SlamDriver d{SlamProcessOptions{}};
  const auto outs = run(d, 5, 10);
  EXPECT_EQ(d.stats().frames_processed, static_cast<int64_t>(outs.size()));
  EXPECT_EQ(d.stats().frames_between_keyframes, 0);
}
