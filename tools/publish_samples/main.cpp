// omnislam-publish-samples: publishes one valid sample message on every channel of the contract,
// repeatedly, so that a viewer such as lcm-spy can be checked against all types.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <iostream>
#include <thread>

#include "omnislam/associations_t.hpp"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/image_t.hpp"
#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/node.h"
#include "omnislam/lcmio/signals.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/particles_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/slam_health_t.hpp"
#include "omnislam/slam_localisation_t.hpp"
#include "omnislam/slam_trajectory_t.hpp"

using namespace omnislam;

namespace {

/// The sensor channels' samples of round k: OMNI_IMAGE, OMNI_FEATURES, ODOMETRY.
void publishSensors(lcmio::Node& node, int64_t k, int64_t utime) {
  image_t img{};
  img.utime = utime, img.seq = k, img.camera_name = "sample", img.width = 4, img.height = 2;
  img.row_stride = 4, img.pixel_format = image_t::FORMAT_GRAY8, img.size = 8, img.data.assign(8, 128);
  node.publish(channels::kOmniImage, img);
  features_t f{};
  f.utime = utime, f.seq = k, f.image_seq = k, f.detector = "sample", f.camera_position_m[2] = 1.8;
  feature_t ft{};
  ft.kind = feature_t::KIND_CEILING_LIGHT, ft.azimuth_rad = 0.5, ft.elevation_rad = 1.0, ft.has_elevation = true;
  ft.covariance[0][0] = ft.covariance[1][1] = 1e-5;
  f.features.push_back(ft);
  f.num_features = 1;
  node.publish(channels::kOmniFeatures, f);
  odometry_t o{};
  o.utime = utime, o.seq = k, o.x_m = 0.1 * k;
  node.publish(channels::kOdometry, o);
}

/// The poses and maps of round k, the SLAM's and the truth's.
void publishPosesAndMaps(lcmio::Node& node, int64_t k, int64_t utime) {
  pose_t p{};
  p.utime = utime, p.seq = k, p.x_m = 0.1 * k, p.num_particles = 10, p.effective_sample_size = 5, p.input_seq = k;
  node.publish(channels::kSlamPose, p);
  p.num_particles = 0, p.effective_sample_size = 0, p.input_seq = -1;
  node.publish(channels::kGroundTruthPose, p);
  map_t m{};
  m.utime = utime, m.seq = k, m.input_seq = k, m.num_candidates = 2;
  landmark_t l{};
  l.id = 1, l.position_m[0] = 4.5, l.position_m[1] = -5.5, l.position_m[2] = 6.5, l.type = 1, l.kind = 1;
  m.landmarks.push_back(l);
  m.num_landmarks = 1;
  node.publish(channels::kSlamMap, m);
  m.input_seq = -1, m.num_candidates = 0;
  m.landmarks[0].type = 0;  // truth: no reliability type (landmark_t)
  node.publish(channels::kGroundTruthMap, m);
}

/// The rest of round k: SLAM_PARTICLES, SLAM_ASSOCIATIONS, SLAM_HEALTH, GROUND_TRUTH_FEATURE_LABELS.
void publishSlamDetails(lcmio::Node& node, int64_t k, int64_t utime) {
  particles_t ps{};
  ps.utime = utime, ps.seq = k, ps.input_seq = k, ps.num_particles = 2;
  ps.x_m = {0.0, 0.1}, ps.y_m = {0.0, 0.0}, ps.theta_rad = {0.0, 0.0}, ps.weight = {0.5, 0.5};
  node.publish(channels::kSlamParticles, ps);
  associations_t as{};
  as.utime = utime, as.seq = k, as.input_seq = k, as.num_features = 1, as.landmark_id = {1};
  node.publish(channels::kSlamAssociations, as);
  slam_health_t h{};
  h.utime = utime, h.seq = k, h.input_seq = k, h.state = slam_health_t::STATE_OK, h.reason = "ok";
  h.num_particles = 10, h.effective_sample_size = 5, h.resampled = true;
  node.publish(channels::kSlamHealth, h);
  feature_labels_t lb{};
  lb.utime = utime, lb.seq = k, lb.features_seq = k, lb.num_features = 1, lb.landmark_id = {1}, lb.source_code = {1};
  node.publish(channels::kGroundTruthFeatureLabels, lb);
}

/// The back end's and the global localiser's of round k: SLAM_TRAJECTORY, SLAM_LOCALISATION.
void publishBackEndAndLocalisation(lcmio::Node& node, int64_t k, int64_t utime) {
  slam_trajectory_t tr{};
  tr.utime = utime, tr.seq = k, tr.input_seq = k, tr.solved_at_utime = utime, tr.ok = true;
  tr.num_landmarks = 1, tr.num_bearings = 4, tr.iterations = 3, tr.final_cost = 0.5;
  tr.num_keyframes = 2, tr.keyframe_utime = {utime - 1'000'000, utime};
  tr.x_m = {0.1 * k - 0.1, 0.1 * k}, tr.y_m = {0.0, 0.0}, tr.theta_rad = {0.0, 0.0};
  node.publish(channels::kSlamTrajectory, tr);
  slam_localisation_t loc{};
  loc.utime = utime, loc.seq = k, loc.input_seq = k, loc.state = slam_localisation_t::STATE_AMBIGUOUS;
  loc.num_hypotheses = 2, loc.num_tracked = 2, loc.num_frames = static_cast<int32_t>(k + 1), loc.num_reported = 2;
  loc.x_m = {0.1 * k, 9.0 - 0.1 * k}, loc.y_m = {0.0, 4.5}, loc.theta_rad = {0.0, 3.14159};
  const std::vector<double> cov{0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.001};
  loc.covariance = {cov, cov}, loc.relative_log_likelihood = {0.0, -0.5};
  loc.frames_explained = {static_cast<int32_t>(k + 1), static_cast<int32_t>(k + 1)}, loc.travel_m = {0.1 * k, 0.1 * k};
  node.publish(channels::kSlamLocalisation, loc);
}

/// Publishes a round every period_s until duration_s has passed or a stop is requested; the rounds.
int64_t publishRounds(lcmio::Node& node, double period_s, double duration_s) {
  const auto t_end = std::chrono::steady_clock::now() + std::chrono::duration<double>(duration_s);
  int64_t k = 0;
  for (; std::chrono::steady_clock::now() < t_end && !lcmio::stopRequested(); ++k) {
    const int64_t utime = 1'700'000'000'000'000 + k * 1'000'000;
    publishSensors(node, k, utime);
    publishPosesAndMaps(node, k, utime);
    publishSlamDetails(node, k, utime);
    publishBackEndAndLocalisation(node, k, utime);
    node.publishStatus();
    // Never past the end: --duration 1 --period 20 ran for 20 s.
    const double left_s = std::chrono::duration<double>(t_end - std::chrono::steady_clock::now()).count();
    node.handleFor(std::max(0.0, std::min(period_s, left_s)));
  }
  return k;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-publish-samples: one sample message per channel, every period"};
  std::string url;
  double period_s = 0.5, duration_s = 10.0;
  cli.add_option("--url", url, "LCM URL (default: $LCM_DEFAULT_URL)");
  cli.add_option("--period", period_s, "seconds between rounds")->check(omnislam::app::FiniteRange(0.01, 60.0));
  cli.add_option("--duration", duration_s, "seconds to run")->check(omnislam::app::FiniteRange(0.0, 3600.0));
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  return app::runMain("omnislam-publish-samples", [&]() -> int {
    lcmio::Node node("publish-samples", app::lcmUrl(url));
    node.setState(process_status_t::STATE_RUNNING);
    const int64_t k = publishRounds(node, period_s, duration_s);
    const bool interrupted = lcmio::stopRequested();
    node.setState(interrupted ? process_status_t::STATE_STOPPING : process_status_t::STATE_FINISHED);
    node.setDetail((interrupted ? "interrupted after " : "finished: ") + std::to_string(k) + " rounds");
    node.publishStatus();
    std::cerr << "published " << k << " rounds" << std::endl;  // what a recording of the bus must hold
    return 0;
  });
}
