// World file parsing: see world_config.h and docs/world-file.md.
#include "omnislam/config/world_config.h"

#include <cmath>

#include "omnislam/core/angles.h"

namespace omnislam::config {
namespace {

std::vector<sim::Light> parseLights(const Node& n) {
  n.rejectUnknownKeys({"height_m", "radius_m", "intensity", "grid", "list"});
  const double height = n.getDouble("height_m", 0.5, 100.0, 6.5);
  const double radius = n.getDouble("radius_m", 0.01, 2.0, 0.15);
  const double intensity = n.getDouble("intensity", 0.05, 10.0, 1.0);
  std::vector<sim::Light> out;
  if (n.has("grid")) {
    const Node g = n.child("grid");
    g.rejectUnknownKeys({"x_m", "y_m"});
    const std::vector<double> xs = g.getDoubles("x_m", g.getStrings("x_m").size(), -1e4, 1e4);
    const std::vector<double> ys = g.getDoubles("y_m", g.getStrings("y_m").size(), -1e4, 1e4);
    int64_t id = 1;
    for (double x : xs)
      for (double y : ys) {
        sim::Light L;
        L.id = id++;
        L.p_LinW_m = Eigen::Vector3d(x, y, height);
        L.radius_m = radius;
        L.intensity = intensity;
        out.push_back(L);
      }
  }
  if (n.has("list")) {
    int64_t id = static_cast<int64_t>(out.size()) + 1;
    for (const Node& item : n.items("list")) {
      item.rejectUnknownKeys({"id", "x_m", "y_m", "z_m", "radius_m", "intensity"});
      sim::Light L;
      L.id = item.getInt("id", 0, 1'000'000'000, id);
      L.p_LinW_m = Eigen::Vector3d(item.getDouble("x_m", -1e4, 1e4), item.getDouble("y_m", -1e4, 1e4),
                                   item.getDouble("z_m", 0.5, 100.0, height));
      L.radius_m = item.getDouble("radius_m", 0.01, 2.0, radius);
      L.intensity = item.getDouble("intensity", 0.05, 10.0, intensity);
      ++id;
      out.push_back(L);
    }
  }
  if (out.empty()) throw ConfigError(n.where("grid") + " or 'list' must give at least one light");
  return out;
}

sim::CameraSetup parseCamera(const Node& n) {
  n.rejectUnknownKeys({"name", "model", "a_px", "b", "c_px", "d", "u0_px", "v0_px", "beta", "width_px", "height_px",
                       "max_zenith_deg", "mounting"});
  sim::CameraSetup c;
  c.name = n.getString("name", "fisheye");
  n.getEnum("model", {"pajdla_bakstein"}, "pajdla_bakstein");
  auto& p = c.intrinsics;
  p.a_px = n.getDouble("a_px", -1e5, 1e5, p.a_px);
  p.b = n.getDouble("b", 1e-3, 1e3, p.b);
  p.c_px = n.getDouble("c_px", -1e5, 1e5, p.c_px);
  p.d = n.getDouble("d", 1e-3, 1e3, p.d);
  p.u0_px = n.getDouble("u0_px", -1e4, 1e5, p.u0_px);
  p.v0_px = n.getDouble("v0_px", -1e4, 1e5, p.v0_px);
  p.beta = n.getDouble("beta", 0.1, 10.0, p.beta);
  p.width_px = static_cast<int>(n.getInt("width_px", 16, 8192, p.width_px));
  p.height_px = static_cast<int>(n.getInt("height_px", 16, 8192, p.height_px));
  p.max_zenith_rad = deg2rad(n.getDouble("max_zenith_deg", 1.0, 179.0, rad2deg(p.max_zenith_rad)));
  if (auto err = camera::PajdlaBaksteinCamera::validate(p)) throw ConfigError(n.where("a_px") + " (camera model): " + *err);
  if (auto m = n.optChild("mounting")) {
    m->rejectUnknownKeys({"x_m", "y_m", "z_m", "yaw_deg"});
    c.mounting.x_m = m->getDouble("x_m", -10.0, 10.0, 0.0);
    c.mounting.y_m = m->getDouble("y_m", -10.0, 10.0, 0.0);
    c.mounting.z_m = m->getDouble("z_m", 0.0, 10.0, 1.8);
    c.mounting.yaw_rad = deg2rad(m->getDouble("yaw_deg", -180.0, 180.0, 0.0));
  }
  return c;
}

void parseTrajectory(const Node& n, sim::World& w) {
  n.rejectUnknownKeys({"start", "speed_mps", "turn_rate_degps", "start_pause_s", "segments"});
  auto& o = w.trajectory_options;
  const Node s = n.child("start");
  s.rejectUnknownKeys({"x_m", "y_m", "theta_deg"});
  o.start = Pose2{s.getDouble("x_m", -1e4, 1e4), s.getDouble("y_m", -1e4, 1e4),
                  wrapAngle(deg2rad(s.getDouble("theta_deg", -360.0, 360.0, 0.0)))};
  o.speed_mps = n.getDouble("speed_mps", 0.01, 5.0, o.speed_mps);
  o.turn_rate_radps = deg2rad(n.getDouble("turn_rate_degps", 0.5, 180.0, rad2deg(o.turn_rate_radps)));
  o.start_pause_s = n.getDouble("start_pause_s", 0.0, 3600.0, o.start_pause_s);
  for (const Node& seg : n.items("segments")) {
    seg.rejectUnknownKeys({"straight_m", "arc_deg", "radius_m", "turn_deg"});
    sim::Segment g;
    const int kinds = seg.has("straight_m") + seg.has("arc_deg") + seg.has("turn_deg");
    if (kinds != 1) throw ConfigError(seg.where("straight_m") + ": each segment needs exactly one of straight_m, arc_deg (with radius_m), turn_deg");
    if (seg.has("straight_m")) {
      g.kind = sim::Segment::Kind::kStraight;
      g.length_m = seg.getDouble("straight_m", 1e-3, 1e4);
    } else if (seg.has("arc_deg")) {
      g.kind = sim::Segment::Kind::kArc;
      g.angle_rad = deg2rad(seg.getDouble("arc_deg", -3600.0, 3600.0));
      g.radius_m = seg.getDouble("radius_m", 0.05, 1e3);
      if (g.angle_rad == 0.0) throw ConfigError(seg.where("arc_deg") + " must not be 0");
    } else {
      g.kind = sim::Segment::Kind::kTurn;
      g.angle_rad = deg2rad(seg.getDouble("turn_deg", -3600.0, 3600.0));
      if (g.angle_rad == 0.0) throw ConfigError(seg.where("turn_deg") + " must not be 0");
    }
    w.segments.push_back(g);
  }
  if (auto err = sim::Trajectory::validate(o, w.segments)) throw ConfigError(n.where("segments") + ": " + *err);
}

void parseImage(const Node& n, sim::ImageNuisance& z) {
  n.rejectUnknownKeys({"noise_sigma_grey", "blur_sigma_px", "background_grey", "light_peak_grey", "samples_per_light",
                       "window_wall", "false_blobs"});
  z.noise_sigma_grey = n.getDouble("noise_sigma_grey", 0.0, 50.0, z.noise_sigma_grey);
  z.blur_sigma_px = n.getDouble("blur_sigma_px", 0.0, 10.0, z.blur_sigma_px);
  z.background_grey = n.getDouble("background_grey", 0.0, 200.0, z.background_grey);
  z.light_peak_grey = n.getDouble("light_peak_grey", 1.0, 255.0, z.light_peak_grey);
  z.samples_per_light = static_cast<int>(n.getInt("samples_per_light", 16, 100000, z.samples_per_light));
  if (auto ww = n.optChild("window_wall")) {
    ww->rejectUnknownKeys({"enabled", "y_m", "band_m", "miss_probability"});
    z.window_wall_enabled = ww->getBool("enabled", z.window_wall_enabled);
    z.window_wall_y_m = ww->getDouble("y_m", -1e4, 1e4, z.window_wall_y_m);
    z.window_band_m = ww->getDouble("band_m", 0.0, 1e3, z.window_band_m);
    z.window_miss_probability = ww->getDouble("miss_probability", 0.0, 1.0, z.window_miss_probability);
  }
  if (auto fb = n.optChild("false_blobs")) {
    fb->rejectUnknownKeys({"per_frame", "radius_px", "peak_grey"});
    z.false_blobs_per_frame = fb->getDouble("per_frame", 0.0, 100.0, z.false_blobs_per_frame);
    z.false_blob_radius_px = fb->getDouble("radius_px", 0.5, 50.0, z.false_blob_radius_px);
    z.false_blob_peak_grey = fb->getDouble("peak_grey", 1.0, 255.0, z.false_blob_peak_grey);
  }
}

}  // namespace

sim::World parseWorld(const Node& root) {
  root.rejectUnknownKeys({"name", "start_utime", "truth_rate_hz", "image_rate_hz", "lights", "camera", "trajectory",
                          "odometry_noise", "image"});
  sim::World w;
  w.name = root.getString("name", "world");
  w.start_utime = root.getInt("start_utime", 1, 4'000'000'000'000'000, w.start_utime);
  w.truth_rate_hz = root.getDouble("truth_rate_hz", 20.0, 1000.0, w.truth_rate_hz);
  w.image_rate_hz = root.getDouble("image_rate_hz", 0.01, 100.0, w.image_rate_hz);
  w.lights = parseLights(root.child("lights"));
  w.camera = parseCamera(root.child("camera"));
  parseTrajectory(root.child("trajectory"), w);
  if (auto o = root.optChild("odometry_noise")) {
    o->rejectUnknownKeys({"distance_sigma_m_per_sqrt_m", "rotation_sigma_rad_per_sqrt_rad",
                          "heading_sigma_rad_per_sqrt_m", "scale_error_sigma", "heading_drift_sigma_rad_per_m"});
    auto& z = w.odometry_noise;
    z.distance_sigma_m_per_sqrt_m = o->getDouble("distance_sigma_m_per_sqrt_m", 0.0, 1.0, z.distance_sigma_m_per_sqrt_m);
    z.rotation_sigma_rad_per_sqrt_rad =
        o->getDouble("rotation_sigma_rad_per_sqrt_rad", 0.0, 1.0, z.rotation_sigma_rad_per_sqrt_rad);
    z.heading_sigma_rad_per_sqrt_m = o->getDouble("heading_sigma_rad_per_sqrt_m", 0.0, 1.0, z.heading_sigma_rad_per_sqrt_m);
    z.scale_error_sigma = o->getDouble("scale_error_sigma", 0.0, 0.5, z.scale_error_sigma);
    z.heading_drift_sigma_rad_per_m =
        o->getDouble("heading_drift_sigma_rad_per_m", 0.0, 0.5, z.heading_drift_sigma_rad_per_m);
  }
  if (auto im = root.optChild("image")) parseImage(*im, w.nuisance);
  if (std::fmod(w.truth_rate_hz, w.image_rate_hz) > 1e-9 && w.image_rate_hz < w.truth_rate_hz) {
    // Images are rendered at truth samples: an image period that is not a whole number of truth
    // periods would put image times between samples.
    const double ratio = w.truth_rate_hz / w.image_rate_hz;
    if (std::abs(ratio - std::round(ratio)) > 1e-9)
      throw ConfigError(root.where("image_rate_hz") + " must divide truth_rate_hz (" +
                        std::to_string(w.truth_rate_hz) + ") a whole number of times");
  }
  if (w.image_rate_hz > w.truth_rate_hz)
    throw ConfigError(root.where("image_rate_hz") + " must be <= truth_rate_hz");
  return w;
}

sim::World loadWorld(const std::string& path) { return parseWorld(Node::loadFile(path)); }

}  // namespace omnislam::config
