// Multi-process test of the walking skeleton: the launcher runs simulator, capture and odometry
// on a private LCM URL and records them with lcm-logger; the log is then checked against the
// truth (image rate and losses, light pixels vs the camera model, odometry noise statistics).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>
#include <numeric>

#include "omnislam/config/world_config.h"
#include "omnislam/core/camera/pajdla_bakstein.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/image_msg.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/process_status_t.hpp"
#include "omnislam/vision/bright_blobs.h"
#include "omnislam/vision/render_lights.h"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

constexpr double kDurationS = 100.0;  // covers the first 18 m straight and the first arc

class SimPipeline : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    run_ = std::make_unique<t::LaunchedRun>(
        "config/launch/sports_hall.yaml", 1,
        std::vector<std::string>{"duration=" + std::to_string(kDurationS), "speedup=25", "seed=7"});
    log_ = run_->log;
  }
  static void TearDownTestSuite() { run_.reset(); }
  static std::unique_ptr<t::LaunchedRun> run_;
  static std::string log_;
};
std::unique_ptr<t::LaunchedRun> SimPipeline::run_;
std::string SimPipeline::log_;

TEST_F(SimPipeline, LauncherRunsTheScenarioToItsEnd) {
  EXPECT_EQ(run_->result.exit_code, 0) << run_->result.output;
  EXPECT_NE(run_->result.output.find("sim finished the scenario"), std::string::npos) << run_->result.output;
  EXPECT_EQ(run_->result.output.find("died"), std::string::npos) << run_->result.output;
}

TEST_F(SimPipeline, ImagesArriveAtOneHertzInSimulatedTimeNoneLost) {
  const auto images = lcmio::readChannel<image_t>(log_, channels::kOmniImage);
  const sim::World world = config::loadWorld(t::sourcePath("config/worlds/sports_hall.yaml"));
  ASSERT_EQ(images.size(), static_cast<size_t>(kDurationS) + 1) << run_->result.output;
  for (size_t i = 0; i < images.size(); ++i) {
    EXPECT_EQ(images[i].seq, static_cast<int64_t>(i)) << "sequence gap at frame " << i;
    EXPECT_EQ(images[i].utime, world.start_utime + static_cast<int64_t>(i) * 1'000'000) << "frame " << i;
    EXPECT_EQ(images[i].width, 640);
    EXPECT_EQ(images[i].height, 480);
  }
}

// The processes lose nothing: odometry answers every truth sample (its last seq equals the
// simulator's). lcm-logger 1.3.1 itself may drop a few small messages when starved of CPU (its
// subscription queue holds 30 messages; docs/user/lcm.md), so the recording is held to >= 99 %.
TEST_F(SimPipeline, TruthAndOdometryAreAtLeastTwentyHertzAndNoneLost) {
  const auto truth = lcmio::readChannel<pose_t>(log_, channels::kGroundTruthPose);
  const auto odo = lcmio::readChannel<odometry_t>(log_, channels::kOdometry);
  const int64_t expected = static_cast<int64_t>(kDurationS * 50) + 1;
  ASSERT_FALSE(truth.empty());
  ASSERT_FALSE(odo.empty());
  EXPECT_EQ(truth.back().seq + 1, expected);
  EXPECT_EQ(odo.back().seq + 1, expected) << "odometry must answer every truth sample";
  EXPECT_GE(static_cast<int64_t>(truth.size()), expected * 99 / 100);
  EXPECT_GE(static_cast<int64_t>(odo.size()), expected * 99 / 100);
  int64_t worst_dt = 0;
  for (size_t i = 1; i < odo.size(); ++i) {
    const int64_t missing = odo[i].seq - odo[i - 1].seq - 1;
    worst_dt = std::max(worst_dt, (odo[i].utime - odo[i - 1].utime) / (missing + 1));
  }
  EXPECT_LE(worst_dt, 50'000) << "odometry period above 50 ms (below 20 Hz)";
}

TEST_F(SimPipeline, LightPixelsAgreeWithTheCameraModelWithinOnePixel) {
  const sim::World world = config::loadWorld(t::sourcePath("config/worlds/sports_hall.yaml"));
  const camera::PajdlaBaksteinCamera cam(world.camera.intrinsics);
  std::map<int64_t, pose_t> truth;
  for (const auto& p : lcmio::readChannel<pose_t>(log_, channels::kGroundTruthPose)) truth[p.utime] = p;
  const auto images = lcmio::readChannel<image_t>(log_, channels::kOmniImage);
  ASSERT_FALSE(images.empty());
  int compared = 0, predicted = 0;
  double worst = 0.0;
  for (const auto& msg : images) {
    const auto it = truth.find(msg.utime);
    ASSERT_NE(it, truth.end()) << "no truth pose at image utime " << msg.utime;
    const auto img = lcmio::decodeImage(msg);
    ASSERT_TRUE(img.has_value());
    const auto blobs = vision::detectBrightBlobs(*img);
    const Pose2 T{it->second.x_m, it->second.y_m, it->second.theta_rad};
    const auto C = vision::cameraInWorld(T, world.camera.mounting);
    for (const sim::Light& L : world.lights) {
      const auto px = cam.project(C.R_WfromC.transpose() * (L.p_LinW_m - C.p_CinW_m));
      if (!px) continue;
      ++predicted;
      // The nearest blob within 4 px is this light's image (lights are > 20 px apart).
      double best = 1e9;
      for (const auto& b : blobs) best = std::min(best, std::hypot(b.u_px - px->x(), b.v_px - px->y()));
      if (best > 4.0) continue;  // missed near the windows, or too faint to pass the threshold
      ++compared;
      worst = std::max(worst, best);
      EXPECT_LT(best, 1.0) << "light " << L.id << " at utime " << msg.utime << ": blob " << best
                           << " px from its projection";
    }
  }
  std::cout << "compared " << compared << " of " << predicted << " predicted light images; worst offset " << worst
            << " px\n";
  EXPECT_GT(compared, predicted * 8 / 10) << "most lights in view must be rendered and found";
}

// Odometry noise, per 1 s window (50 truth samples): the distance residual after removing the
// per-run scale error is N(0, sigma_d^2 |ds|); the heading residual after removing the per-run
// drift is N(0, sigma_r^2 |dtheta| + sigma_h^2 |ds|). Their estimated spreads must match the
// world file's values (about 100 windows: a +-40 % band is about 4 standard errors).
TEST_F(SimPipeline, OdometryDriftsFromTruthByTheConfiguredNoise) {
  const sim::World world = config::loadWorld(t::sourcePath("config/worlds/sports_hall.yaml"));
  const auto& nz = world.odometry_noise;
  std::map<int64_t, pose_t> truth;
  for (const auto& p : lcmio::readChannel<pose_t>(log_, channels::kGroundTruthPose)) truth[p.utime] = p;
  const auto odo = lcmio::readChannel<odometry_t>(log_, channels::kOdometry);
  ASSERT_FALSE(odo.empty()) << "no ODOMETRY recorded";
  struct W {
    double ds_t, dth_t, ds_o, dth_o;
  };
  std::map<int64_t, odometry_t> by_utime;
  for (const auto& o : odo) by_utime[o.utime] = o;
  std::vector<W> ws;
  const int64_t t0 = odo.front().utime;
  for (int64_t k = 1; k <= static_cast<int64_t>(kDurationS); ++k) {
    const int64_t ua = t0 + (k - 1) * 1'000'000, ub = t0 + k * 1'000'000;
    // A window whose end points the logger happened to drop is skipped.
    if (!by_utime.count(ua) || !by_utime.count(ub) || !truth.count(ua) || !truth.count(ub)) continue;
    const auto& a = by_utime[ua];
    const auto& b = by_utime[ub];
    const auto& ta = truth[a.utime];
    const auto& tb = truth[b.utime];
    const Pose2 dt = Pose2{ta.x_m, ta.y_m, ta.theta_rad}.between(Pose2{tb.x_m, tb.y_m, tb.theta_rad});
    const Pose2 dodo = Pose2{a.x_m, a.y_m, a.theta_rad}.between(Pose2{b.x_m, b.y_m, b.theta_rad});
    ws.push_back({std::hypot(dt.x_m, dt.y_m), dt.theta_rad, std::hypot(dodo.x_m, dodo.y_m), dodo.theta_rad});
  }
  // Windows where the robot moves (the start pause has none).
  std::vector<W> moving;
  for (const auto& w : ws)
    if (w.ds_t > 0.1) moving.push_back(w);
  ASSERT_GT(moving.size(), 80u);
  double sxy = 0, sxx = 0;
  for (const auto& w : moving) {
    sxy += (w.ds_o - w.ds_t) * w.ds_t;
    sxx += w.ds_t * w.ds_t;
  }
  const double k_hat = sxy / sxx;
  double z2 = 0;
  for (const auto& w : moving) {
    const double e = w.ds_o - (1 + k_hat) * w.ds_t;
    z2 += e * e / w.ds_t;
  }
  const double sigma_d_hat = std::sqrt(z2 / static_cast<double>(moving.size() - 1));
  // Heading: remove the drift (rad per metre) by regression, then normalise by the model's sigma.
  double hxy = 0, hxx = 0;
  for (const auto& w : moving) {
    hxy += wrapAngle(w.dth_o - w.dth_t) * w.ds_t;
    hxx += w.ds_t * w.ds_t;
  }
  const double drift_hat = hxy / hxx;
  double zh = 0;
  for (const auto& w : moving) {
    const double e = wrapAngle(w.dth_o - w.dth_t) - drift_hat * w.ds_t;
    const double var = nz.rotation_sigma_rad_per_sqrt_rad * nz.rotation_sigma_rad_per_sqrt_rad * std::abs(w.dth_t) +
                       nz.heading_sigma_rad_per_sqrt_m * nz.heading_sigma_rad_per_sqrt_m * w.ds_t;
    zh += e * e / var;
  }
  const double heading_z_std = std::sqrt(zh / static_cast<double>(moving.size() - 1));
  std::cout << "windows " << moving.size() << ": scale error " << k_hat << ", sigma_d " << sigma_d_hat
            << " m/sqrt(m) (configured " << nz.distance_sigma_m_per_sqrt_m << "), heading drift " << drift_hat
            << " rad/m, heading residual z-std " << heading_z_std << " (1 expected)\n";
  EXPECT_NEAR(sigma_d_hat, nz.distance_sigma_m_per_sqrt_m, 0.4 * nz.distance_sigma_m_per_sqrt_m);
  EXPECT_NEAR(heading_z_std, 1.0, 0.4);
  EXPECT_LT(std::abs(k_hat), 4 * nz.scale_error_sigma + 0.02);
  EXPECT_LT(std::abs(drift_hat), 4 * nz.heading_drift_sigma_rad_per_m + 0.01);
}

TEST_F(SimPipeline, EveryProcessReportsStatusWithoutErrors) {
  std::map<std::string, process_status_t> last;
  for (const auto& s : lcmio::readChannel<process_status_t>(log_, channels::kProcessStatus)) last[s.name] = s;
  for (const char* name : {"sim", "capture", "odometry"}) {
    ASSERT_TRUE(last.count(name)) << "no PROCESS_STATUS from " << name;
    const auto& s = last[name];
    EXPECT_EQ(s.decode_errors, 0) << name << ": " << s.last_error;
    EXPECT_EQ(s.rejected_inputs, 0) << name << ": " << s.last_error;
    EXPECT_EQ(s.sequence_gaps, 0) << name;
  }
  EXPECT_EQ(last["sim"].state, +process_status_t::STATE_FINISHED);  // + : LCM constants have no out-of-line definition
}

}  // namespace
