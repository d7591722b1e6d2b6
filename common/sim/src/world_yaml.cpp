// Writing a generated world as a world file (docs/user/world-file.md), and the detection range of its
// lamps: see world_generator.h.
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "omnislam/core/angles.h"
#include "omnislam/sim/feature_sim.h"
#include "omnislam/sim/world_generator.h"

namespace omnislam::sim {
namespace {

/// 10 significant digits: enough for the generator's mm and 0.1 deg, and the same bytes everywhere.
std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", v == 0.0 ? 0.0 : v);  // no "-0"
  return buf;
}

void writeCamera(std::ostringstream& y, const CameraSetup& c) {
  if (c.model != CameraModelKind::kPajdlaBakstein)
    throw std::invalid_argument("worldToYaml: writes Pajdla-Bakstein cameras only");
  const auto& k = c.intrinsics;
  const auto& m = c.mounting;
  y << "camera:\n  name: " << c.name << "\n  model: pajdla_bakstein\n"
    << "  a_px: " << num(k.a_px) << "\n  b: " << num(k.b) << "\n  c_px: " << num(k.c_px) << "\n  d: " << num(k.d)
    << "\n  u0_px: " << num(k.u0_px) << "\n  v0_px: " << num(k.v0_px) << "\n  beta: " << num(k.beta)
    << "\n  width_px: " << k.width_px << "\n  height_px: " << k.height_px
    << "\n  max_zenith_deg: " << num(rad2deg(k.max_zenith_rad)) << "\n  mounting: {x_m: " << num(m.x_m)
    << ", y_m: " << num(m.y_m) << ", z_m: " << num(m.z_m) << ", yaw_deg: " << num(rad2deg(m.yaw_rad))
    << ", pitch_deg: " << num(rad2deg(m.pitch_rad)) << ", roll_deg: " << num(rad2deg(m.roll_rad)) << "}\n";
}

void writeTrajectory(std::ostringstream& y, const World& w) {
  const TrajectoryOptions& o = w.trajectory_options;
  y << "trajectory:\n  start: {x_m: " << num(o.start.x_m) << ", y_m: " << num(o.start.y_m)
    << ", theta_deg: " << num(rad2deg(o.start.theta_rad)) << "}\n  speed_mps: " << num(o.speed_mps)
    << "\n  turn_rate_degps: " << num(rad2deg(o.turn_rate_radps)) << "\n  start_pause_s: " << num(o.start_pause_s)
    << "\n  segments:\n";
  for (const Segment& s : w.segments) {
    if (s.kind == Segment::Kind::kStraight) y << "    - {straight_m: " << num(s.length_m) << "}\n";
    if (s.kind == Segment::Kind::kArc)
      y << "    - {arc_deg: " << num(rad2deg(s.angle_rad)) << ", radius_m: " << num(s.radius_m) << "}\n";
    if (s.kind == Segment::Kind::kTurn) y << "    - {turn_deg: " << num(rad2deg(s.angle_rad)) << "}\n";
  }
}

void writeNoise(std::ostringstream& y, const World& w) {
  const OdometryNoise& n = w.odometry_noise;
  if (n.model != OdometryModel::kWheel) throw std::invalid_argument("worldToYaml: writes wheel odometry noise only");
  y << "odometry_noise:\n  model: wheel\n  distance_sigma_m_per_sqrt_m: " << num(n.distance_sigma_m_per_sqrt_m)
    << "\n  rotation_sigma_rad_per_sqrt_rad: " << num(n.rotation_sigma_rad_per_sqrt_rad)
    << "\n  heading_sigma_rad_per_sqrt_m: " << num(n.heading_sigma_rad_per_sqrt_m)
    << "\n  scale_error_sigma: " << num(n.scale_error_sigma)
    << "\n  heading_drift_sigma_rad_per_m: " << num(n.heading_drift_sigma_rad_per_m) << "\n";
  const ImageNuisance& z = w.nuisance;
  y << "image:\n  noise_sigma_grey: " << num(z.noise_sigma_grey) << "\n  blur_sigma_px: " << num(z.blur_sigma_px)
    << "\n  background_grey: " << num(z.background_grey) << "\n  light_peak_grey: " << num(z.light_peak_grey)
    << "\n  samples_per_light: " << z.samples_per_light
    << "\n  window_wall: {enabled: " << (z.window_wall_enabled ? "true" : "false")
    << ", y_m: " << num(z.window_wall_y_m) << ", band_m: " << num(z.window_band_m)
    << ", miss_probability: " << num(z.window_miss_probability)
    << "}\n  false_blobs: {per_frame: " << num(z.false_blobs_per_frame)
    << ", radius_px: " << num(z.false_blob_radius_px) << ", peak_grey: " << num(z.false_blob_peak_grey) << "}\n";
}

}  // namespace

std::string worldToYaml(const World& w, const std::vector<std::string>& header) {
  if (w.room) throw std::invalid_argument("worldToYaml: writes ceiling-light worlds only");
  std::ostringstream y;
  for (const std::string& line : header) y << "# " << line << "\n";
  y << "name: " << w.name << "\nstart_utime: " << w.start_utime << "\ntruth_rate_hz: " << num(w.truth_rate_hz)
    << "\nimage_rate_hz: " << num(w.image_rate_hz) << "\n";
  if (w.hall)
    y << "hall: {x_min_m: " << num(w.hall->x_min_m) << ", x_max_m: " << num(w.hall->x_max_m)
      << ", y_min_m: " << num(w.hall->y_min_m) << ", y_max_m: " << num(w.hall->y_max_m) << "}\n";
  y << "lights:\n  list:\n";
  for (const Light& L : w.lights)
    y << "    - {id: " << L.id << ", x_m: " << num(L.p_LinW_m.x()) << ", y_m: " << num(L.p_LinW_m.y())
      << ", z_m: " << num(L.p_LinW_m.z()) << ", radius_m: " << num(L.radius_m) << ", intensity: " << num(L.intensity)
      << "}\n";
  writeCamera(y, w.camera);
  writeTrajectory(y, w);
  writeNoise(y, w);
  return y.str();
}

double detectionRange_m(const World& world, double radius_m, double height_m, double min_area_px) {
  const auto camera = makeCamera(world.camera);
  const Eigen::Vector3d cam =
      Eigen::Vector3d(world.camera.mounting.x_m, world.camera.mounting.y_m, world.camera.mounting.z_m);
  double range = 0.0;
  for (double dx = 0.0; dx <= 1000.0; dx += 0.05) {  // the lamp ahead of a robot at the origin
    const Eigen::Vector3d p(cam.x() + dx, cam.y(), height_m);
    const auto img = discImage(*camera, world.camera.mounting, Pose2{}, p, radius_m);
    if (img && img->area_px >= min_area_px) range = (p - cam).norm();
    else if (dx > 1.0) break;  // beyond the first metre, the first miss ends the search
  }
  return range;
}

}  // namespace omnislam::sim
