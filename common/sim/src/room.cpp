// Room geometry, its vertical-line landmarks and a brute-force ray caster: see room.h.
#include "omnislam/sim/room.h"

#include <cmath>
#include <limits>
#include <sstream>

namespace omnislam::sim {
namespace {

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

bool finite3(const Eigen::Vector3d& v) { return v.allFinite(); }

bool rgbOk(const Eigen::Vector3d& c) { return finite3(c) && c.minCoeff() >= 0.0 && c.maxCoeff() <= 255.0; }

/// Panel boundaries along a wall, as distances from `from`: b[0] = 0 .. b[n] = length. The last
/// boundary is the wall's end even when the widths miss it by validate()'s 1 cm: a shortfall left a
/// gap that rays passed through, an excess a wall sticking out past the corner.
std::vector<double> panelBounds(const Wall& w) {
  const double len = (w.to_m - w.from_m).norm();
  std::vector<double> b{0.0};
  for (size_t j = 0; j < w.panels.size(); ++j) {
    const bool last = j + 1 == w.panels.size();
    b.push_back(last ? len : b.back() + w.panels[j].width_m);
  }
  return b;
}

std::array<Eigen::Vector2d, 4> boxCorners(const Box& bx) {
  const Eigen::Vector2d ax(std::cos(bx.yaw_rad), std::sin(bx.yaw_rad)), ay(-ax.y(), ax.x());
  const double hx = 0.5 * bx.size_x_m, hy = 0.5 * bx.size_y_m;
  // Counter-clockwise from (+x, -y): side i runs from corner i to corner i+1 and faces
  // +x, +y, -x, -y for i = 0..3.
  return {bx.centre_m + hx * ax - hy * ay, bx.centre_m + hx * ax + hy * ay, bx.centre_m - hx * ax + hy * ay,
          bx.centre_m - hx * ax - hy * ay};
}

Facet verticalFacet(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double z0, double z1,
                    const Eigen::Vector3d& rgb) {
  Facet f;
  f.vertical = true;
  f.a = a;
  f.b = b;
  f.z_min = z0;
  f.z_max = z1;
  f.rgb = rgb;
  const Eigen::Vector2d e = (b - a).normalized();
  f.normal = Eigen::Vector2d(-e.y(), e.x());
  return f;
}

}  // namespace

std::optional<std::string> Room::validate() const {
  if (!(std::isfinite(height_m) && height_m >= 1.0 && height_m <= 20.0)) return "height_m must be in [1, 20]";
  if (!rgbOk(floor_rgb)) return "floor_rgb must be 3 numbers in [0, 255]";
  if (!rgbOk(ceiling_rgb)) return "ceiling_rgb must be 3 numbers in [0, 255]";
  if (walls.empty()) return "walls must list at least one wall";
  for (size_t i = 0; i < walls.size(); ++i) {
    const Wall& w = walls[i];
    const std::string tag = "walls[" + std::to_string(i) + "]";
    const double len = (w.to_m - w.from_m).norm();
    if (!(std::isfinite(len) && len >= 0.05)) return tag + ": from and to must be >= 0.05 m apart";
    if (w.panels.empty()) return tag + ".panels must list at least one panel";
    double sum = 0.0;
    for (size_t j = 0; j < w.panels.size(); ++j) {
      const WallPanel& p = w.panels[j];
      const std::string ptag = tag + ".panels[" + std::to_string(j) + "]";
      if (!rgbOk(p.rgb)) return ptag + ".rgb must be 3 numbers in [0, 255]";
      const bool last = j + 1 == w.panels.size();
      if (p.width_m <= 0.0 && !last) return ptag + ".width_m must be > 0 (only the last panel may fill the rest)";
      if (p.width_m > 0.0 && p.width_m < 0.005) return ptag + ".width_m must be >= 0.005 m";
      if (p.width_m > 0.0) sum += p.width_m;
    }
    const bool fills = w.panels.back().width_m <= 0.0;
    if (fills && sum > len - 0.005)
      return tag + ": the panels' widths (" + std::to_string(sum) + " m) leave nothing for the last panel of a " +
             std::to_string(len) + " m wall";
    if (!fills && std::abs(sum - len) > 0.01)
      return tag + ": the panels' widths sum to " + std::to_string(sum) + " m but the wall is " + std::to_string(len) +
             " m long (give the last panel no width_m to fill the rest)";
  }
  for (const Box& b : boxes) {
    const std::string tag = "box '" + b.name + "'";
    if (!(b.size_x_m >= 0.01 && b.size_y_m >= 0.01)) return tag + ": sizes must be >= 0.01 m";
    if (!(b.z_min_m >= 0.0 && b.z_max_m <= height_m && b.z_max_m > b.z_min_m + 0.005))
      return tag + ": need 0 <= z_min_m < z_max_m <= the room's height_m";
    for (const auto& c : b.side_rgb)
      if (!rgbOk(c)) return tag + ": side colours must be 3 numbers in [0, 255]";
    if (!rgbOk(b.top_rgb)) return tag + ": top colour must be 3 numbers in [0, 255]";
  }
  return std::nullopt;
}

std::vector<Facet> Room::facets() const {
  std::vector<Facet> out;
  for (const Wall& w : walls) {
    const Eigen::Vector2d dir = (w.to_m - w.from_m).normalized();
    const std::vector<double> b = panelBounds(w);
    for (size_t j = 0; j < w.panels.size(); ++j)
      out.push_back(verticalFacet(w.from_m + b[j] * dir, w.from_m + b[j + 1] * dir, 0.0, height_m, w.panels[j].rgb));
  }
  for (const Box& bx : boxes) {
    const auto c = boxCorners(bx);
    for (int i = 0; i < 4; ++i)
      out.push_back(verticalFacet(c[static_cast<size_t>(i)], c[static_cast<size_t>((i + 1) % 4)], bx.z_min_m,
                                  bx.z_max_m, bx.side_rgb[static_cast<size_t>(i)]));
    for (double z : {bx.z_max_m, bx.z_min_m}) {
      if (z <= 0.0 || z >= height_m) continue;  // on the floor / at the ceiling: never seen
      Facet f;
      f.vertical = false;
      f.centre = bx.centre_m;
      f.axis_x = Eigen::Vector2d(std::cos(bx.yaw_rad), std::sin(bx.yaw_rad));
      f.axis_y = Eigen::Vector2d(-f.axis_x.y(), f.axis_x.x());
      f.half_x = 0.5 * bx.size_x_m;
      f.half_y = 0.5 * bx.size_y_m;
      f.z_min = f.z_max = z;
      f.rgb = bx.top_rgb;
      out.push_back(f);
    }
  }
  return out;
}

std::vector<RoomLine> Room::lines() const {
  std::vector<RoomLine> out;
  int64_t id = 1;
  for (size_t i = 0; i < walls.size(); ++i) {
    const Wall& w = walls[i];
    const Eigen::Vector2d dir = (w.to_m - w.from_m).normalized();
    const std::vector<double> b = panelBounds(w);
    for (size_t j = 0; j + 1 < w.panels.size(); ++j) {
      if ((w.panels[j].rgb - w.panels[j + 1].rgb).norm() < 1e-9) continue;  // same colour: no edge
      RoomLine L;
      L.id = id++;
      L.p_m = w.from_m + b[j + 1] * dir;
      L.z_min_m = 0.0;
      L.z_max_m = height_m;
      std::ostringstream s;
      s << "wall " << i << " panels " << j << "|" << j + 1;
      L.what = s.str();
      out.push_back(L);
    }
  }
  // Wall ends: room corners (ends closer than 1 cm are one corner).
  std::vector<Eigen::Vector2d> corners;
  for (const Wall& w : walls)
    for (const Eigen::Vector2d& p : {w.from_m, w.to_m}) {
      bool seen = false;
      for (const auto& q : corners) seen = seen || (p - q).norm() < 0.01;
      if (!seen) corners.push_back(p);
    }
  for (size_t k = 0; k < corners.size(); ++k) {
    RoomLine L;
    L.id = id++;
    L.p_m = corners[k];
    L.z_min_m = 0.0;
    L.z_max_m = height_m;
    L.what = "corner " + std::to_string(k);
    out.push_back(L);
  }
  for (const Box& bx : boxes) {
    if (!bx.lines) continue;
    const auto c = boxCorners(bx);
    for (size_t k = 0; k < 4; ++k) {
      RoomLine L;
      L.id = id++;
      L.p_m = c[k];
      L.z_min_m = bx.z_min_m;
      L.z_max_m = bx.z_max_m;
      L.what = "box " + bx.name + " corner " + std::to_string(k);
      out.push_back(L);
    }
  }
  return out;
}

double hitFacet(const Facet& f, const Eigen::Vector3d& o, double c, double s, double tan_el) {
  if (f.vertical) {
    const Eigen::Vector2d d(c, s), e = f.b - f.a, ao = f.a - o.head<2>();
    const double den = cross2(d, e);
    if (std::abs(den) < 1e-15) return -1.0;
    const double t = cross2(ao, e) / den;
    const double u = cross2(ao, d) / den;
    if (!(t > 1e-9) || u < 0.0 || u > 1.0) return -1.0;
    const double z = o.z() + t * tan_el;
    if (z < f.z_min || z > f.z_max) return -1.0;
    return t;
  }
  if (tan_el == 0.0) return -1.0;
  const double t = (f.z_min - o.z()) / tan_el;
  if (!(t > 1e-9)) return -1.0;
  const Eigen::Vector2d p(o.x() + t * c - f.centre.x(), o.y() + t * s - f.centre.y());
  if (std::abs(p.dot(f.axis_x)) > f.half_x || std::abs(p.dot(f.axis_y)) > f.half_y) return -1.0;
  return t;
}

RayHit firstHit(const std::vector<Facet>& facets, double height_m, const Eigen::Vector3d& o, double c, double s,
                double tan_el) {
  RayHit h;
  h.t_h_m = std::numeric_limits<double>::infinity();
  h.facet = -3;
  if (tan_el < 0.0) {
    h.t_h_m = -o.z() / tan_el;
    h.facet = -1;
  } else if (tan_el > 0.0) {
    h.t_h_m = (height_m - o.z()) / tan_el;
    h.facet = -2;
  }
  for (size_t i = 0; i < facets.size(); ++i) {
    const double t = hitFacet(facets[i], o, c, s, tan_el);
    if (t > 0.0 && t < h.t_h_m) {
      h.t_h_m = t;
      h.facet = static_cast<int>(i);
    }
  }
  return h;
}

}  // namespace omnislam::sim
