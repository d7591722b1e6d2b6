// Feature-level simulation of a ceiling-light world: see feature_sim.h.
#include "omnislam/sim/feature_sim.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "omnislam/core/camera/bearing_jacobians.h"
#include "omnislam/core/camera/mounting.h"
#include "omnislam/sim/image_clock.h"
#include "omnislam/sim/odometry_sim.h"
#include "omnislam/sim/trajectory.h"

namespace omnislam::sim {
namespace {

/// Point of W in the camera frame of the robot at `robot`.
Eigen::Vector3d worldToCamera(const camera::CameraMounting& m, const Pose2& robot, const Eigen::Vector3d& p_W) {
  const double c = std::cos(robot.theta_rad), s = std::sin(robot.theta_rad);
  const double dx = p_W.x() - robot.x_m, dy = p_W.y() - robot.y_m;
  const Eigen::Vector3d p_R(c * dx + s * dy, -s * dx + c * dy, p_W.z());
  return camera::pointRobotToCamera(m, p_R);
}

/// The bearing the detector publishes for a centroid at px: robot-frame angles and covariance
/// (sigma_px^2 J J^T through the unprojection and the mounting). Nothing off the model.
std::optional<SimFeature> featureAt(const camera::CameraModel& camera, const camera::CameraMounting& m,
                                    const Eigen::Vector2d& px, double sigma_px) {
  Eigen::Matrix<double, 3, 2> J_d_px;
  const auto d_C = camera.unproject(px, &J_d_px);
  if (!d_C) return std::nullopt;
  const Eigen::Vector3d d_R = camera::directionCameraToRobot(m, *d_C);
  const auto J_ae_dR = camera::azimuthElevationJacobian(d_R);
  if (!J_ae_dR) return std::nullopt;  // straight up: the azimuth is undefined (never drawn exactly)
  const Eigen::Matrix2d J_ae_px = *J_ae_dR * camera::rotationCameraToRobot(m) * J_d_px;
  SimFeature f;
  const Eigen::Vector2d ae = camera::azimuthElevation(d_R);
  f.azimuth_rad = ae.x();
  f.elevation_rad = ae.y();
  f.covariance_rad2 = sigma_px * sigma_px * J_ae_px * J_ae_px.transpose();
  f.covariance_rad2(1, 0) = f.covariance_rad2(0, 1);  // exactly symmetric, as receivers check
  f.px = px;
  return f;
}

/// The detected lamps of one frame, then the clutter.
std::vector<SimFeature> detect(const World& w, const camera::CameraModel& camera, const Pose2& robot,
                               const FeatureSimOptions& o, std::mt19937_64& rng) {
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const ImageNuisance& z = w.nuisance;
  std::vector<SimFeature> out;
  for (const Light& L : w.lights) {
    const auto img = discImage(camera, w.camera.mounting, robot, L.p_LinW_m, L.radius_m, o.rim_points);
    if (!img || img->area_px < o.min_area_px) continue;
    const bool near_windows = z.window_wall_enabled && std::abs(L.p_LinW_m.y() - z.window_wall_y_m) < z.window_band_m;
    const double miss_draw = u01(rng);
    if (near_windows ? miss_draw < z.window_miss_probability : miss_draw < o.miss_probability) continue;
    const Eigen::Vector2d px = img->centre_px + o.pixel_sigma_px * Eigen::Vector2d(n01(rng), n01(rng));
    auto f = featureAt(camera, w.camera.mounting, px, o.pixel_sigma_px);
    if (!f) continue;
    f->light_id = L.id;
    f->area_px = img->area_px;
    out.push_back(*f);
  }
  const double rate = z.false_blobs_per_frame * o.clutter_published_fraction;
  const int n_clutter = rate > 0.0 ? std::poisson_distribution<int>(rate)(rng) : 0;
  for (int i = 0; i < n_clutter; ++i) {
    for (int attempt = 0; attempt < 100; ++attempt) {  // uniform over the usable pixels
      const Eigen::Vector2d px(u01(rng) * camera.widthPx() - 0.5, u01(rng) * camera.heightPx() - 0.5);
      if (auto f = featureAt(camera, w.camera.mounting, px, o.pixel_sigma_px)) {
        out.push_back(*f);
        break;
      }
    }
  }
  std::shuffle(out.begin(), out.end(), rng);  // detections come in image order, not map order
  return out;
}

}  // namespace

std::optional<DiscImage> discImage(const camera::CameraModel& camera, const camera::CameraMounting& mounting,
                                   const Pose2& robot, const Eigen::Vector3d& p_LinW_m, double radius_m,
                                   int rim_points) {
  const auto centre = camera.project(worldToCamera(mounting, robot, p_LinW_m));
  if (!centre) return std::nullopt;
  std::vector<Eigen::Vector2d> rim;
  for (int i = 0; i < rim_points; ++i) {
    const double a = 2.0 * kPi * i / rim_points;
    const Eigen::Vector3d p = p_LinW_m + radius_m * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0);
    const auto px = camera.project(worldToCamera(mounting, robot, p));
    if (!px) return std::nullopt;  // cut by the border of the field of view: the detector drops it
    rim.push_back(*px);
  }
  double twice_area = 0.0;
  for (size_t i = 0; i < rim.size(); ++i) {
    const Eigen::Vector2d& a = rim[i];
    const Eigen::Vector2d& b = rim[(i + 1) % rim.size()];
    twice_area += a.x() * b.y() - b.x() * a.y();
  }
  return DiscImage{0.5 * std::abs(twice_area), *centre};
}

SimRun simulateFeatures(const World& world, uint64_t odometry_seed, uint64_t detector_seed,
                        const FeatureSimOptions& options) {
  if (world.room || world.lights.empty())
    throw std::invalid_argument("feature simulation: needs a world of ceiling lights (this one has none)");
  if (!(options.pixel_sigma_px > 0.0) || !(options.min_area_px >= 0.0) || options.rim_points < 3 ||
      !(options.miss_probability >= 0.0 && options.miss_probability <= 1.0) ||
      !(options.clutter_published_fraction >= 0.0 && options.clutter_published_fraction <= 1.0))
    throw std::invalid_argument("feature simulation: an option is out of its range (feature_sim.h)");
  const Trajectory traj(world.trajectory_options, world.segments);
  const auto camera = makeCamera(world.camera);
  OdometrySimulator odo(world.odometry_noise, odometry_seed);
  std::mt19937_64 rng(detector_seed);
  ImageClock clock(world.start_utime, world.image_rate_hz, world.truth_rate_hz);
  SimRun run;
  // After a kidnap the odometry feels the drive's motion from where it was: K * drive(t), with
  // K = drive(at) * drive(to)^-1 continuous at the kidnap.
  Pose2 felt;
  if (options.kidnap) {
    const FeatureSimOptions::Kidnap& k = *options.kidnap;
    if (!(k.at_s >= 0.0 && k.at_s <= traj.duration_s() && k.to_s >= 0.0 && k.to_s <= traj.duration_s()))
      throw std::invalid_argument("feature simulation: a kidnap's times must be within the drive's [0, " +
                                  std::to_string(traj.duration_s()) + "] s");
    felt = traj.at(k.at_s).pose.compose(traj.at(k.to_s).pose.inverse());
  }
  const double dt = 1.0 / world.truth_rate_hz;
  const int64_t n_steps = static_cast<int64_t>(std::floor(traj.duration_s() / dt + 1e-9));
  for (int64_t k = 0; k <= n_steps; ++k) {  // as omnislam-sim: t = k dt, utime rounded
    SimTruthStep s;
    s.t_s = k * dt;
    const bool carried = options.kidnap && s.t_s >= options.kidnap->at_s;
    const TrajectorySample ts = traj.at(carried ? s.t_s - options.kidnap->at_s + options.kidnap->to_s : s.t_s);
    s.truth = ts.pose;
    s.odometry = odo.step(carried ? felt.compose(ts.pose) : ts.pose);  // the motion, not the jump
    if (k > 0) {  // as omnislam-odometry: from the previous odometry pose
      const Pose2 d = run.steps.back().odometry.between(s.odometry);
      s.v_mps = d.x_m / dt;
      s.omega_radps = d.theta_rad / dt;
    }
    const int64_t utime = world.start_utime + static_cast<int64_t>(std::llround(s.t_s * 1e6));
    if (clock.take(utime)) {
      SimFrame f;
      f.index = static_cast<int64_t>(run.frames.size());
      f.truth_step = k;
      f.t_s = s.t_s;
      f.features = detect(world, *camera, s.truth, options, rng);
      run.frames.push_back(std::move(f));
    }
    run.steps.push_back(s);
  }
  run.odometry_scale_error = odo.scaleError();
  run.odometry_heading_drift_rad_per_m = odo.headingDrift_rad_per_m();
  return run;
}

}  // namespace omnislam::sim
