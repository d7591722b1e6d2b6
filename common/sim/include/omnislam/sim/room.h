// An indoor room of paper 002's kind (docs/results/room-scenario.md): walls made of coloured panels, floor,
// ceiling and free-standing boxes (cabinets, table legs and tops). Every vertical boundary between
// two differently coloured surfaces (and every room or box corner) is a vertical-line landmark,
// measured by azimuth only. Pure geometry (Eigen + std): the renderer (common/vision render_room)
// and the tests use it.
//
// Frames and units: world frame W, x/y on the floor, z up, metres; colours are R, G, B in [0, 255].
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace omnislam::sim {

/// A straight run of wall from `from` to `to`, floor to ceiling, split along its length into panels.
struct WallPanel {
  double width_m = 0.0;                           ///< along the wall; <= 0: fill the rest of the wall
  Eigen::Vector3d rgb = Eigen::Vector3d::Zero();  ///< R, G, B, 0..255
};
struct Wall {
  Eigen::Vector2d from_m = Eigen::Vector2d::Zero();
  Eigen::Vector2d to_m = Eigen::Vector2d::Zero();
  std::vector<WallPanel> panels;  ///< in order from `from`; the last one may fill the rest
};

/// A free-standing box (cabinet, table leg, table top): a rectangle of size_x x size_y rotated by
/// yaw about its centre, from z_min to z_max. side_rgb[i] colours the side facing local
/// +x, +y, -x, -y (i = 0..3); top_rgb the top and bottom.
struct Box {
  std::string name;
  Eigen::Vector2d centre_m = Eigen::Vector2d::Zero();
  double size_x_m = 0.5, size_y_m = 0.5, yaw_rad = 0.0;
  double z_min_m = 0.0, z_max_m = 1.0;
  std::array<Eigen::Vector3d, 4> side_rgb{};
  Eigen::Vector3d top_rgb = Eigen::Vector3d::Zero();
  bool lines = true;  ///< its corners are landmarks (false e.g. for a thin table top)
};

/// A vertical-line landmark: the line x = p_m, z in [z_min_m, z_max_m].
struct RoomLine {
  int64_t id = 0;  ///< 1.. in the order of walls then boxes
  Eigen::Vector2d p_m = Eigen::Vector2d::Zero();
  double z_min_m = 0.0, z_max_m = 0.0;
  std::string what;  ///< e.g. "wall 2 panel 3|4", "corner", "box cabinet corner 1"
};

/// A planar piece of the scene the ray caster tests. Vertical: the quad over the segment a..b,
/// z in [z_min, z_max]. Horizontal: the rectangle (centre, axes, half sizes) at height z_min.
struct Facet {
  bool vertical = true;
  Eigen::Vector2d a = Eigen::Vector2d::Zero(), b = Eigen::Vector2d::Zero();  ///< vertical: ends
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();                          ///< horizontal
  Eigen::Vector2d axis_x = Eigen::Vector2d::UnitX(), axis_y = Eigen::Vector2d::UnitY();
  double half_x = 0.0, half_y = 0.0;
  double z_min = 0.0, z_max = 0.0;
  Eigen::Vector3d rgb = Eigen::Vector3d::Zero();
  Eigen::Vector2d normal = Eigen::Vector2d::Zero();  ///< vertical facets: unit normal (either side)
};

struct Room {
  double height_m = 2.6;
  Eigen::Vector3d floor_rgb{120, 110, 100};
  Eigen::Vector3d ceiling_rgb{225, 225, 220};
  std::vector<Wall> walls;
  std::vector<Box> boxes;

  /// Checks the geometry; a message naming the item (wall i, panel j, box name) or nothing.
  std::optional<std::string> validate() const;
  /// The scene as facets (walls' panels, boxes' sides and tops/bottoms); floor and ceiling are
  /// implicit (z = 0 and z = height_m).
  std::vector<Facet> facets() const;
  /// The vertical-line landmarks: panel boundaries where the colour changes, wall ends (room
  /// corners, merged within 1 cm) and box corners; ids 1.. in that order.
  std::vector<RoomLine> lines() const;
};

/// What a ray hits first.
struct RayHit {
  double t_h_m = 0.0;  ///< horizontal distance from the ray's origin to the hit [m]
  int facet = -1;      ///< index into facets(); -1 floor, -2 ceiling, -3 nothing
};

/// First hit of the ray from `origin` (z inside the room) along azimuth `az` (cos, sin) and
/// elevation with tangent `tan_el`, among `facets` and the floor/ceiling of a room of `height_m`.
/// Brute force over all facets (the renderer bins them by azimuth for speed).
RayHit firstHit(const std::vector<Facet>& facets, double height_m, const Eigen::Vector3d& origin, double cos_az,
                double sin_az, double tan_el);

/// Horizontal distance along the ray to a facet, or a negative number when it misses.
double hitFacet(const Facet& f, const Eigen::Vector3d& origin, double cos_az, double sin_az, double tan_el);

}  // namespace omnislam::sim
