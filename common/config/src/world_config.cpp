// World file parsing: see world_config.h and docs/user/world-file.md.
#include "omnislam/config/world_config.h"

#include <Eigen/QR>

#include <cmath>
#include <set>

#include "omnislam/config/options_parse.h"
#include "omnislam/config/world_camera_table.h"
#include "omnislam/core/angles.h"
#include "omnislam/core/limits.h"

namespace omnislam::config {
namespace {

/// The most lights a world may have: GROUND_TRUTH_MAP carries every light, and a map message holds
/// at most kMaxMapLandmarks (100 000). A grid is the product of its two lists, so it is
/// checked before it is built: 3000 values each way asked for 9 million lights, 10 000 for 3 GB.
constexpr size_t kMaxLights = kMaxMapLandmarks;

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
    if (static_cast<double>(xs.size()) * static_cast<double>(ys.size()) > static_cast<double>(kMaxLights))
      throw ConfigError(g.where("x_m") + ": a grid of " + std::to_string(xs.size()) + " x " +
                        std::to_string(ys.size()) + " lights, more than " + std::to_string(kMaxLights) +
                        " (the most a GROUND_TRUTH_MAP carries)");
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
    // Ids name the lights in GROUND_TRUTH_MAP and in the evaluation's association scores; the
    // grid's are 1..N by construction, so a repeat can only come from the list.
    const size_t in_grid = out.size();
    std::set<int64_t> ids;
    for (const sim::Light& L : out) ids.insert(L.id);
    int64_t id = static_cast<int64_t>(in_grid) + 1;
    const std::vector<Node> list = n.items("list");
    if (in_grid + list.size() > kMaxLights)
      throw ConfigError(n.where("list") + ": " + std::to_string(in_grid) + " lights in the grid and " +
                        std::to_string(list.size()) + " in the list, more than " + std::to_string(kMaxLights) +
                        " (the most a GROUND_TRUTH_MAP carries)");
    for (const Node& item : list) {
      item.rejectUnknownKeys({"id", "x_m", "y_m", "z_m", "radius_m", "intensity"});
      sim::Light L;
      L.id = item.getInt("id", 0, 1'000'000'000, id);
      if (!ids.insert(L.id).second)
        throw ConfigError(item.where("id") + ": light id " + std::to_string(L.id) +
                          " is used twice (the grid numbers its " + std::to_string(in_grid) + " lights 1.." +
                          std::to_string(in_grid) +
                          ", a listed light without id takes the next number; give each light its own id)");
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

camera::CameraMounting parseMounting(const Node& n) {
  camera::CameraMounting m;
  if (auto mo = n.optChild("mounting")) {
    mo->rejectUnknownKeys({"x_m", "y_m", "z_m", "yaw_deg", "pitch_deg", "roll_deg"});
    m.x_m = mo->getDouble("x_m", -10.0, 10.0, 0.0);
    m.y_m = mo->getDouble("y_m", -10.0, 10.0, 0.0);
    m.z_m = mo->getDouble("z_m", 0.0, 10.0, 1.8);
    m.yaw_rad = deg2rad(mo->getDouble("yaw_deg", -180.0, 180.0, 0.0));
    m.pitch_rad = deg2rad(mo->getDouble("pitch_deg", -90.0, 90.0, 0.0));
    m.roll_rad = deg2rad(mo->getDouble("roll_deg", -180.0, 180.0, 0.0));
  }
  return m;
}

/// rho(theta) (theta = elevation of a catadioptric camera, beta - pi/2) fitted by least squares
/// over the usable radii: the initial guess of ScaramuzzaCamera::project (which refines it).
std::vector<double> fitInvpol(camera::ScaramuzzaParams p) {
  p.invpol = {0.5 * (p.min_radius_px + 1.0)};  // placeholder, only to construct the model
  const camera::ScaramuzzaCamera cam(p);
  const double lo = p.min_radius_px, hi = cam.maxRadiusPx();
  constexpr int kSamples = 200, kDegree = 6;
  Eigen::MatrixXd A(kSamples, kDegree + 1);
  Eigen::VectorXd b(kSamples);
  for (int i = 0; i < kSamples; ++i) {
    const double rho = lo + (hi - lo) * i / (kSamples - 1);
    const double theta = cam.offCentreAngle(rho) - kPi / 2.0;
    double pw = 1.0;
    for (int k = 0; k <= kDegree; ++k, pw *= theta) A(i, k) = pw;
    b(i) = rho;
  }
  const Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
  return std::vector<double>(x.data(), x.data() + x.size());
}

/// The Scaramuzza model of a room world: polynomials, size and distortion centre by hand (their
/// ranges depend on each other), the other keys through scaramuzzaFields().
camera::ScaramuzzaParams parseScaramuzza(const Node& n) {
  camera::ScaramuzzaParams p;
  p.optics = n.getEnum("optics", {"catadioptric", "dioptric"}, "catadioptric") == "catadioptric"
                 ? camera::OcamOptics::kCatadioptric
                 : camera::OcamOptics::kDioptric;
  p.pol = n.getDoubles("pol", n.getStrings("pol").size(), -1e6, 1e6);
  if (p.pol.size() < 2 || p.pol.size() > 16)
    throw ConfigError(n.where("pol") + " must have 2 to 16 coefficients (got " + std::to_string(p.pol.size()) + ")");
  p.width_px = static_cast<int>(n.getInt("width_px", 16, 8192));
  p.height_px = static_cast<int>(n.getInt("height_px", 16, 8192));
  p.xc_row_px = n.getDouble("xc_row_px", -0.5, p.height_px - 0.5);
  p.yc_col_px = n.getDouble("yc_col_px", -0.5, p.width_px - 0.5);
  parseFields(n, p, scaramuzzaFields());
  if (!(p.max_elevation_rad > p.min_elevation_rad))
    throw ConfigError(n.where("max_elevation_deg") + " must be > min_elevation_deg");
  if (n.has("invpol")) {
    p.invpol = n.getDoubles("invpol", n.getStrings("invpol").size(), -1e6, 1e6);
    if (p.invpol.size() > 64) throw ConfigError(n.where("invpol") + " must have 1 to 64 coefficients");
  } else {
    p.invpol = {1.0};
    if (auto err = camera::ScaramuzzaCamera::validate(p))
      throw ConfigError(n.where("pol") + " (camera model): " + *err);
    p.invpol = fitInvpol(p);
  }
  if (auto err = camera::ScaramuzzaCamera::validate(p)) throw ConfigError(n.where("pol") + " (camera model): " + *err);
  return p;
}

sim::CameraSetup parseCamera(const Node& n) {
  sim::CameraSetup c;
  const std::string model = n.getEnum("model", {"pajdla_bakstein", "scaramuzza"}, "pajdla_bakstein");
  if (model == "scaramuzza") {
    n.rejectUnknownKeysIn(keysOf(scaramuzzaFields(), {"name", "model", "optics", "pol", "invpol", "xc_row_px",
                                                      "yc_col_px", "width_px", "height_px", "mounting"}));
    c.name = n.getString("name", "catadioptric");
    c.model = sim::CameraModelKind::kScaramuzza;
    c.scaramuzza = parseScaramuzza(n);
    c.mounting = parseMounting(n);
    return c;
  }
  n.rejectUnknownKeysIn(keysOf(pajdlaBaksteinFields(), {"name", "model", "mounting"}));
  c.name = n.getString("name", "fisheye");
  parseFields(n, c.intrinsics, pajdlaBaksteinFields());
  if (auto err = camera::PajdlaBaksteinCamera::validate(c.intrinsics))
    throw ConfigError(n.where("a_px") + " (camera model): " + *err);
  c.mounting = parseMounting(n);
  return c;
}

Eigen::Vector3d getRgb(const Node& n, const std::string& key) {
  const std::vector<double> v = n.getDoubles(key, 3, 0.0, 255.0);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}
Eigen::Vector3d getRgb(const Node& n, const std::string& key, const Eigen::Vector3d& def) {
  return n.has(key) ? getRgb(n, key) : def;
}

sim::Room parseRoom(const Node& n) {
  n.rejectUnknownKeys({"height_m", "floor_rgb", "ceiling_rgb", "walls", "boxes"});
  sim::Room r;
  r.height_m = n.getDouble("height_m", 1.0, 20.0, r.height_m);
  r.floor_rgb = getRgb(n, "floor_rgb", r.floor_rgb);
  r.ceiling_rgb = getRgb(n, "ceiling_rgb", r.ceiling_rgb);
  for (const Node& w : n.items("walls")) {
    w.rejectUnknownKeys({"from", "to", "panels"});
    sim::Wall wall;
    const auto a = w.getDoubles("from", 2, -1e4, 1e4), b = w.getDoubles("to", 2, -1e4, 1e4);
    wall.from_m = Eigen::Vector2d(a[0], a[1]);
    wall.to_m = Eigen::Vector2d(b[0], b[1]);
    const std::vector<Node> panels = w.items("panels");
    for (size_t j = 0; j < panels.size(); ++j) {
      const Node& p = panels[j];
      p.rejectUnknownKeys({"width_m", "rgb"});
      sim::WallPanel panel;
      const bool last = j + 1 == panels.size();
      panel.width_m = last && !p.has("width_m") ? 0.0 : p.getDouble("width_m", 0.005, 1e4);
      panel.rgb = getRgb(p, "rgb");
      wall.panels.push_back(panel);
    }
    r.walls.push_back(wall);
    sim::Room so_far;  // the walls up to this one (the earlier ones passed): the message names this one
    so_far.height_m = r.height_m;
    so_far.walls = r.walls;
    if (auto err = so_far.validate()) throw ConfigError(w.where("panels") + ": " + *err);
  }
  if (n.has("boxes")) {
    for (const Node& b : n.items("boxes")) {
      b.rejectUnknownKeys({"name", "x_m", "y_m", "size_x_m", "size_y_m", "yaw_deg", "z_min_m", "z_max_m", "rgb",
                           "rgb_x_plus", "rgb_y_plus", "rgb_x_minus", "rgb_y_minus", "top_rgb", "lines"});
      sim::Box bx;
      bx.name = b.getString("name", "box" + std::to_string(r.boxes.size()));
      bx.centre_m = Eigen::Vector2d(b.getDouble("x_m", -1e4, 1e4), b.getDouble("y_m", -1e4, 1e4));
      bx.size_x_m = b.getDouble("size_x_m", 0.01, 100.0);
      bx.size_y_m = b.getDouble("size_y_m", 0.01, 100.0);
      bx.yaw_rad = deg2rad(b.getDouble("yaw_deg", -360.0, 360.0, 0.0));
      bx.z_min_m = b.getDouble("z_min_m", 0.0, r.height_m, 0.0);
      bx.z_max_m = b.getDouble("z_max_m", 0.0, r.height_m);
      if (!(bx.z_max_m > bx.z_min_m + 0.005)) throw ConfigError(b.where("z_max_m") + " must be > z_min_m + 0.005");
      const Eigen::Vector3d rgb = getRgb(b, "rgb");
      bx.side_rgb = {getRgb(b, "rgb_x_plus", rgb), getRgb(b, "rgb_y_plus", rgb), getRgb(b, "rgb_x_minus", rgb),
                     getRgb(b, "rgb_y_minus", rgb)};
      bx.top_rgb = getRgb(b, "top_rgb", rgb);
      bx.lines = b.getBool("lines", true);
      r.boxes.push_back(bx);
    }
  }
  if (auto err = r.validate()) throw ConfigError(n.where("walls") + ": " + *err);
  return r;
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
    if (kinds != 1)
      throw ConfigError(seg.where("straight_m") +
                        ": each segment needs exactly one of straight_m, arc_deg (with radius_m), turn_deg");
    if (seg.has("radius_m") && !seg.has("arc_deg"))
      throw ConfigError(seg.where("radius_m") +
                        " belongs to an arc_deg segment (a turn_deg turns on the spot, a "
                        "straight_m has no radius)");
    if (seg.has("straight_m")) {
      g.kind = sim::Segment::Kind::kStraight;
      g.length_m = seg.getDouble("straight_m", 1e-3, 1e4);
    } else if (seg.has("arc_deg")) {
      g.kind = sim::Segment::Kind::kArc;
      g.angle_rad = deg2rad(seg.getDouble("arc_deg", -3600.0, 3600.0));
      g.radius_m = seg.getDouble("radius_m", 0.05, 1e3);
      if (g.angle_rad == 0.0) throw ConfigError(seg.where("arc_deg") + " must not be 0");
      // Driven at speed_mps, an arc turns at speed / radius: at most the turn_rate_degps limit of
      // 180 deg/s, or a truth sample's turn could exceed half a turn and wrap the wrong way.
      if (o.speed_mps / g.radius_m > kPi)
        throw ConfigError(seg.where("radius_m") + " must be >= speed_mps / pi = " + std::to_string(o.speed_mps / kPi) +
                          " m (an arc turns at speed_mps / radius_m, at most 180 deg/s)");
    } else {
      g.kind = sim::Segment::Kind::kTurn;
      g.angle_rad = deg2rad(seg.getDouble("turn_deg", -3600.0, 3600.0));
      if (g.angle_rad == 0.0) throw ConfigError(seg.where("turn_deg") + " must not be 0");
    }
    w.segments.push_back(g);
  }
  if (auto err = sim::Trajectory::validate(o, w.segments)) throw ConfigError(n.where("segments") + ": " + *err);
}

sim::HallBounds parseHall(const Node& n) {
  n.rejectUnknownKeys({"x_min_m", "x_max_m", "y_min_m", "y_max_m"});
  sim::HallBounds h;
  h.x_min_m = n.getDouble("x_min_m", -1e4, 1e4);
  h.x_max_m = n.getDouble("x_max_m", -1e4, 1e4);
  h.y_min_m = n.getDouble("y_min_m", -1e4, 1e4);
  h.y_max_m = n.getDouble("y_max_m", -1e4, 1e4);
  if (!(h.x_max_m > h.x_min_m)) throw ConfigError(n.where("x_max_m") + " must be > x_min_m");
  if (!(h.y_max_m > h.y_min_m)) throw ConfigError(n.where("y_max_m") + " must be > y_min_m");
  return h;
}

void parseImage(const Node& n, sim::ImageNuisance& z) {
  n.rejectUnknownKeys({"noise_sigma_grey", "blur_sigma_px", "background_grey", "light_peak_grey", "samples_per_light",
                       "supersample", "shading", "window_wall", "false_blobs"});
  z.noise_sigma_grey = n.getDouble("noise_sigma_grey", 0.0, 50.0, z.noise_sigma_grey);
  z.blur_sigma_px = n.getDouble("blur_sigma_px", 0.0, 10.0, z.blur_sigma_px);
  z.background_grey = n.getDouble("background_grey", 0.0, 200.0, z.background_grey);
  z.light_peak_grey = n.getDouble("light_peak_grey", 1.0, 255.0, z.light_peak_grey);
  z.samples_per_light = static_cast<int>(n.getInt("samples_per_light", 16, 100000, z.samples_per_light));
  z.supersample = static_cast<int>(n.getInt("supersample", 1, 4, z.supersample));
  z.shading = n.getDouble("shading", 0.0, 0.9, z.shading);
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
  root.rejectUnknownKeys({"name", "start_utime", "truth_rate_hz", "image_rate_hz", "lights", "room", "camera",
                          "trajectory", "odometry_noise", "image", "hall"});
  sim::World w;
  w.name = root.getString("name", "world");
  w.start_utime = root.getInt("start_utime", 1, 4'000'000'000'000'000, w.start_utime);
  w.truth_rate_hz = root.getDouble("truth_rate_hz", 20.0, 1000.0, w.truth_rate_hz);
  w.image_rate_hz = root.getDouble("image_rate_hz", 0.01, 100.0, w.image_rate_hz);
  if (root.has("lights") == root.has("room"))
    throw ConfigError(root.where("lights") +
                      " or 'room': a world needs exactly one of them (ceiling lights or a room)");
  if (root.has("lights")) w.lights = parseLights(root.child("lights"));
  if (root.has("room")) w.room = parseRoom(root.child("room"));
  if (auto h = root.optChild("hall")) w.hall = parseHall(*h);
  w.camera = parseCamera(root.child("camera"));
  parseTrajectory(root.child("trajectory"), w);
  if (auto o = root.optChild("odometry_noise")) {
    auto& z = w.odometry_noise;
    const std::string model = o->getEnum("model", {"wheel", "translate_rotate"}, "wheel");
    if (model == "translate_rotate") {
      o->rejectUnknownKeys({"model", "err_tran_m_per_sqrt_m", "err_rot_rad_per_sqrt_rad", "err_drift_rad_per_sqrt_m"});
      z.model = sim::OdometryModel::kTranslateRotate;
      z.err_tran_m_per_sqrt_m = o->getDouble("err_tran_m_per_sqrt_m", 0.0, 1.0, z.err_tran_m_per_sqrt_m);
      z.err_rot_rad_per_sqrt_rad = o->getDouble("err_rot_rad_per_sqrt_rad", 0.0, 1.0, z.err_rot_rad_per_sqrt_rad);
      z.err_drift_rad_per_sqrt_m = o->getDouble("err_drift_rad_per_sqrt_m", 0.0, 1.0, z.err_drift_rad_per_sqrt_m);
    } else {
      o->rejectUnknownKeys({"model", "distance_sigma_m_per_sqrt_m", "rotation_sigma_rad_per_sqrt_rad",
                            "heading_sigma_rad_per_sqrt_m", "scale_error_sigma", "heading_drift_sigma_rad_per_m"});
      z.distance_sigma_m_per_sqrt_m =
          o->getDouble("distance_sigma_m_per_sqrt_m", 0.0, 1.0, z.distance_sigma_m_per_sqrt_m);
      z.rotation_sigma_rad_per_sqrt_rad =
          o->getDouble("rotation_sigma_rad_per_sqrt_rad", 0.0, 1.0, z.rotation_sigma_rad_per_sqrt_rad);
      z.heading_sigma_rad_per_sqrt_m =
          o->getDouble("heading_sigma_rad_per_sqrt_m", 0.0, 1.0, z.heading_sigma_rad_per_sqrt_m);
      z.scale_error_sigma = o->getDouble("scale_error_sigma", 0.0, 0.5, z.scale_error_sigma);
      z.heading_drift_sigma_rad_per_m =
          o->getDouble("heading_drift_sigma_rad_per_m", 0.0, 0.5, z.heading_drift_sigma_rad_per_m);
    }
  }
  if (auto im = root.optChild("image")) parseImage(*im, w.nuisance);
  if (std::fmod(w.truth_rate_hz, w.image_rate_hz) > 1e-9 && w.image_rate_hz < w.truth_rate_hz) {
    // Images are rendered at truth samples: an image period that is not a whole number of truth
    // periods would put image times between samples.
    const double ratio = w.truth_rate_hz / w.image_rate_hz;
    if (std::abs(ratio - std::round(ratio)) > 1e-9)
      throw ConfigError(root.where("image_rate_hz") + " must divide truth_rate_hz (" + std::to_string(w.truth_rate_hz) +
                        ") a whole number of times");
  }
  if (w.image_rate_hz > w.truth_rate_hz) throw ConfigError(root.where("image_rate_hz") + " must be <= truth_rate_hz");
  if (w.room && !(w.camera.mounting.z_m > 0.0 && w.camera.mounting.z_m < w.room->height_m)) {
    // Above the ceiling every ray hits the ceiling's plane from outside: blank images, no error.
    const Node cam = root.child("camera");
    const auto mo = cam.optChild("mounting");
    const std::string key = mo ? mo->where("z_m") : cam.where("mounting") + " (z_m 1.8 by default)";
    throw ConfigError(key + " must be inside the room, in (0, " + std::to_string(w.room->height_m) +
                      ") m (room.height_m), got " + std::to_string(w.camera.mounting.z_m));
  }
  return w;
}

sim::World loadWorld(const std::string& path) { return parseWorld(Node::loadFile(path)); }

}  // namespace omnislam::config
