// Room worlds (docs/user/world-file.md, "Room worlds"): the room's landmarks (panel boundaries of
// different colour, corners, box corners) and the ray caster, the Scaramuzza camera from the world
// file, and bad values rejected with the key named.
#include <gtest/gtest.h>

#include <cmath>

#include "omnislam/config/world_config.h"
#include "omnislam/core/angles.h"

using namespace omnislam;

namespace {

const std::string kCamera = R"(
camera:
  model: scaramuzza
  pol: [-30.0119, 0.0, 0.012275, -1.05054e-4, 4.07406e-7]
  xc_row_px: 239.5
  yc_col_px: 319.5
  width_px: 640
  height_px: 480
  min_radius_px: 40.0
  max_radius_px: 236.0
  min_elevation_deg: -5.0
  max_elevation_deg: 65.0
  mounting: {z_m: 0.5}
trajectory: {start: {x_m: 1, y_m: 1}, segments: [{straight_m: 1.0}]}
)";

const std::string kRoom = R"(
room:
  height_m: 2.5
  walls:
    - from: [0, 0]
      to: [4, 0]
      panels:
        - {width_m: 1.0, rgb: [200, 200, 200]}
        - {width_m: 0.1, rgb: [50, 50, 50]}
        - {width_m: 1.0, rgb: [50, 50, 50]}
        - {rgb: [200, 200, 200]}
    - from: [4, 0]
      to: [4, 3]
      panels: [{rgb: [100, 150, 200]}]
    - from: [4, 3]
      to: [0, 3]
      panels: [{rgb: [100, 150, 200]}]
    - from: [0, 3]
      to: [0, 0]
      panels: [{rgb: [100, 150, 200]}]
  boxes:
    - {name: cab, x_m: 2, y_m: 2, size_x_m: 0.5, size_y_m: 0.3, z_max_m: 1.5, rgb: [10, 20, 30]}
    - {name: top, x_m: 3, y_m: 1, size_x_m: 0.5, size_y_m: 0.3, z_min_m: 0.7, z_max_m: 0.75, rgb: [10, 20, 30], lines: false}
)";

sim::World load(const std::string& text) { return config::parseWorld(config::Node::loadString(text, "w.yaml")); }

void expectError(const std::string& text, const std::string& key) {
  try {
    load(text);
    ADD_FAILURE() << "accepted a world that should fail on " << key;
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << "message: " << e.what();
  }
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto p = s.find(from);
  EXPECT_NE(p, std::string::npos) << from;
  if (p != std::string::npos) s.replace(p, from.size(), to);
  return s;
}

}  // namespace

TEST(RoomWorld, LinesAreColourBoundariesCornersAndBoxCorners) {
  const sim::World w = load(kRoom + kCamera);
  ASSERT_TRUE(w.room.has_value());
  const auto lines = w.room->lines();
  // Panel boundaries at 1.0 (grey|dark) and 2.1 (dark|grey); 1.1 is dark|dark: no line. Then the 4
  // corners, then the cabinet's 4 corners; the table top has none.
  ASSERT_EQ(lines.size(), 2u + 4u + 4u);
  EXPECT_NEAR(lines[0].p_m.x(), 1.0, 1e-12);
  EXPECT_NEAR(lines[1].p_m.x(), 2.1, 1e-12);
  for (size_t i = 0; i < lines.size(); ++i) EXPECT_EQ(lines[i].id, static_cast<int64_t>(i + 1));
  EXPECT_NEAR(lines[6].p_m.x(), 2.25, 1e-12);
  EXPECT_NEAR(lines[6].p_m.y(), 1.85, 1e-12);
  EXPECT_DOUBLE_EQ(lines[6].z_max_m, 1.5);
  // Facets: 4 + 1 + 1 + 1 panels, 2 x (4 sides) + tops/bottoms above the floor (cab top, table top
  // and bottom).
  EXPECT_EQ(w.room->facets().size(), 7u + 8u + 3u);
}

TEST(RoomWorld, RayCasterFindsTheNearestSurface) {
  const sim::World w = load(kRoom + kCamera);
  const auto facets = w.room->facets();
  const Eigen::Vector3d o(1.0, 1.0, 0.5);
  // Straight towards -y: the south wall at 1 m, on panel 0 (x = 1.0 is its end).
  auto h = sim::firstHit(facets, 2.5, o, 0.0, -1.0, 0.0);
  EXPECT_NEAR(h.t_h_m, 1.0, 1e-12);
  EXPECT_EQ(h.facet, 0);
  // Towards the cabinet (centre 2, 2, x 1.75..2.25, y 1.85..2.15): its -y side at y = 1.85.
  const Eigen::Vector2d d = Eigen::Vector2d(1.0, 1.0).normalized();
  h = sim::firstHit(facets, 2.5, o, d.x(), d.y(), 0.0);
  ASSERT_GE(h.facet, 0);
  EXPECT_TRUE(facets[static_cast<size_t>(h.facet)].vertical);
  EXPECT_NEAR(h.t_h_m, 0.85 * std::sqrt(2.0), 1e-9);
  // Steeply up: the ceiling 2 m above at 45 deg -> 2 m away horizontally... unless a wall is nearer.
  h = sim::firstHit(facets, 2.5, o, 0.0, -1.0, 1.0);
  EXPECT_NEAR(h.t_h_m, 1.0, 1e-12);  // the south wall (z = 1.5 there) comes first
  h = sim::firstHit(facets, 2.5, Eigen::Vector3d(3.0, 1.5, 0.5), 0.0, 1.0, 4.0);
  EXPECT_EQ(h.facet, -2);  // ceiling at 0.5 m
  EXPECT_NEAR(h.t_h_m, 0.5, 1e-12);

  // Panel widths 5 mm short of the wall (validate allows 1 cm): the wall still reaches its corner.
  const std::string short_panels = replace(kRoom + kCamera, "        - {rgb: [200, 200, 200]}\n",
                                           "        - {width_m: 1.895, rgb: [200, 200, 200]}\n");
  const auto f2 = load(short_panels).room->facets();
  h = sim::firstHit(f2, 2.5, Eigen::Vector3d(3.998, 1.0, 0.5), 0.0, -1.0, 0.0);
  EXPECT_GE(h.facet, 0);  // before: no facet (the ceiling's colour seen through a 5 mm gap)
  EXPECT_NEAR(h.t_h_m, 1.0, 1e-12);
}

TEST(RoomWorld, ScaramuzzaCameraFromTheWorldFile) {
  const sim::World w = load(kRoom + kCamera);
  ASSERT_EQ(w.camera.model, sim::CameraModelKind::kScaramuzza);
  EXPECT_EQ(w.camera.name, "catadioptric");
  EXPECT_FALSE(w.camera.scaramuzza.invpol.empty());  // fitted
  const auto cam = sim::makeCamera(w.camera);
  // Round trip through the fitted invpol (initial guess) and Newton.
  for (double el_deg : {-4.0, 0.0, 20.0, 60.0}) {
    const double el = deg2rad(el_deg), az = 0.7;
    const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const auto px = cam->project(d);
    ASSERT_TRUE(px.has_value()) << el_deg;
    const auto back = cam->unproject(*px);
    ASSERT_TRUE(back.has_value());
    EXPECT_LT((*back - d).norm(), 1e-9);
  }
  EXPECT_EQ(sim::cameraCentrePx(w.camera), Eigen::Vector2d(319.5, 239.5));
}

TEST(RoomWorld, BadValuesNameTheKey) {
  const std::string ok = kRoom + kCamera;
  expectError(replace(ok, "- {width_m: 0.1, rgb: [50, 50, 50]}", "- {width_m: 0.1, rgb: [50, 50, 500]}"),
              "room.walls[0].panels[1].rgb");
  expectError(replace(ok, "- {width_m: 1.0, rgb: [200, 200, 200]}", "- {width_m: 3.5, rgb: [200, 200, 200]}"),
              "room.walls[0].panels");
  expectError(replace(ok, "- {width_m: 1.0, rgb: [200, 200, 200]}", "- {width: 1.0, rgb: [200, 200, 200]}"),
              "room.walls[0].panels[0].width' is not a known key");
  expectError(replace(ok, "height_m: 2.5", "height_m: 0.5"), "room.height_m");
  expectError(replace(ok, "z_max_m: 1.5", "z_max_m: 3.5"), "room.boxes[0].z_max_m");
  expectError(replace(ok, "size_x_m: 0.5, size_y_m: 0.3, z_max_m: 1.5", "size_x_m: 0.0, size_y_m: 0.3, z_max_m: 1.5"),
              "room.boxes[0].size_x_m");
  expectError(replace(ok, "to: [4, 0]", "to: [0, 0.01]"), "room.walls[0]");
  // A later wall is named by its own index, in the key and in the reason.
  expectError(replace(ok, "to: [4, 3]", "to: [4, 0.01]"), "room.walls[1].panels': walls[1]: from and to");
  expectError(ok + "lights: {height_m: 6.5, grid: {x_m: [1.0], y_m: [1.0]}}\n", "lights");
  expectError(replace(ok, "room:", "rooms:"), "rooms");
  expectError(replace(ok, "pol: [-30.0119, 0.0, 0.012275, -1.05054e-4, 4.07406e-7]", "pol: [30.0, 0.0, 0.01]"),
              "camera.pol");
  expectError(replace(ok, "max_elevation_deg: 65.0", "max_elevation_deg: -10.0"), "camera.max_elevation_deg");
  expectError(replace(ok, "xc_row_px: 239.5", "xc_row_px: 600"), "camera.xc_row_px");
  expectError(replace(ok, "model: scaramuzza", "model: scaramuzza\n  a_px: 200"), "a_px");
  expectError(ok + "image: {supersample: 9}\n", "image.supersample");
  expectError(ok + "image: {shading: 1.5}\n", "image.shading");
  // A camera above the ceiling (room height 2.5 m) saw nothing but the ceiling's colour, silently.
  expectError(replace(ok, "mounting: {z_m: 0.5}", "mounting: {z_m: 2.6}"),
              "key 'camera.mounting.z_m' must be inside the room, in (0, 2.500000) m (room.height_m), got 2.6");
  expectError(replace(ok, "mounting: {z_m: 0.5}", "mounting: {z_m: 0.0}"),
              "camera.mounting.z_m' must be inside the room");
  // radius_m outside an arc is refused, not ignored (a turn on the spot where an arc was meant).
  expectError(replace(ok, "segments: [{straight_m: 1.0}]", "segments: [{turn_deg: 90, radius_m: 2.0}]"),
              "trajectory.segments[0].radius_m' belongs to an arc_deg segment");
  // An arc turning faster than 180 deg/s (speed 0.3 m/s on 0.05 m): a truth sample's turn wrapped.
  expectError(
      replace(ok, "segments: [{straight_m: 1.0}]", "speed_mps: 0.3, segments: [{arc_deg: 3600, radius_m: 0.05}]"),
      "trajectory.segments[0].radius_m' must be >= speed_mps / pi");
}
