// Saved maps: YAML text, atomic writes (see map_file.h).
#include "omnislam/runtime/map_file.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <unordered_set>

#include "omnislam/config/yaml_node.h"
#include "omnislam/runtime/atomic_file.h"

namespace omnislam::runtime {

namespace {

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

}  // namespace

std::string mapToYaml(const SavedMap& map) {
  std::ostringstream o;
  o << "# omnislam saved map: the best particle's landmarks in the map frame W (metres, m^2).\n"
    << "# Written by omnislam-slam; load with --load-map (format: procs/slam/map_file.h).\n"
    << "format: omnislam-map\nversion: 1\nutime: " << map.utime << "\nlandmarks:";
  if (map.landmarks.empty()) o << " []";
  o << "\n";
  for (const slam::Landmark& L : map.landmarks) {
    o << "  - {id: " << L.id
      << ", kind: " << (L.kind == slam::LandmarkKind::kVerticalLine ? "vertical_line" : "point3d")
      << ", type: " << (L.type == slam::LandmarkType::kTypeI ? 1 : 2) << ", counter: " << L.counter << ", position_m: ["
      << num(L.p_LinW_m.x()) << ", " << num(L.p_LinW_m.y()) << ", " << num(L.p_LinW_m.z()) << "], covariance_m2: [";
    for (int i = 0; i < 9; ++i) o << (i ? ", " : "") << num(L.cov_LinW_m2(i / 3, i % 3));
    o << "]}\n";
  }
  return o.str();
}

void saveMapAtomically(const SavedMap& map, const std::string& path) {
  const std::string text = mapToYaml(map);
  writeFileAtomically(path, text.data(), text.size());
}

SavedMap loadMap(const std::string& path) {
  using config::ConfigError;
  const config::Node root = config::Node::loadFile(path);
  root.rejectUnknownKeys({"format", "version", "utime", "landmarks"});
  root.getEnum("format", {"omnislam-map"});
  root.getInt("version", 1, 1);
  SavedMap m;
  m.utime = root.getInt("utime", INT64_MIN, INT64_MAX, 0);
  const std::vector<config::Node> items = root.items("landmarks");
  // The map is published as SLAM_MAP, which carries at most 100 000 landmarks (lcmio::Limits).
  if (items.size() > kMaxSavedLandmarks)
    throw ConfigError(root.where("landmarks") + " holds " + std::to_string(items.size()) + " landmarks, more than " +
                      std::to_string(kMaxSavedLandmarks) + " (the most a map message carries)");
  std::unordered_set<std::uint64_t> ids;  // a linear scan per landmark took 10 s for 20 000 under ASan
  for (const config::Node& n : items) {
    n.rejectUnknownKeys({"id", "kind", "type", "counter", "position_m", "covariance_m2"});
    slam::Landmark L;
    L.id = static_cast<std::uint64_t>(n.getInt("id", 0, INT64_MAX));
    L.kind = n.getEnum("kind", {"point3d", "vertical_line"}) == "vertical_line" ? slam::LandmarkKind::kVerticalLine
                                                                                : slam::LandmarkKind::kPoint3D;
    L.type = n.getInt("type", 1, 2) == 1 ? slam::LandmarkType::kTypeI : slam::LandmarkType::kTypeII;
    L.counter = static_cast<int>(n.getInt("counter", 0, INT32_MAX));
    const auto p = n.getDoubles("position_m", 3, -1e6, 1e6);
    L.p_LinW_m = Eigen::Vector3d(p[0], p[1], p[2]);
    const auto c = n.getDoubles("covariance_m2", 9, -1e6, 1e6);
    for (int i = 0; i < 9; ++i) L.cov_LinW_m2(i / 3, i % 3) = c[static_cast<std::size_t>(i)];
    const bool symmetric = (L.cov_LinW_m2 - L.cov_LinW_m2.transpose()).cwiseAbs().maxCoeff() <=
                           1e-9 * (1.0 + L.cov_LinW_m2.cwiseAbs().maxCoeff());
    if (!symmetric || Eigen::LLT<Eigen::Matrix3d>(L.cov_LinW_m2).info() != Eigen::Success)
      throw ConfigError(n.where("covariance_m2") + " of landmark " + std::to_string(L.id) +
                        " must be symmetric positive definite");
    if (!ids.insert(L.id).second) throw ConfigError(n.where("id") + ": duplicate landmark id " + std::to_string(L.id));
    m.landmarks.push_back(L);
  }
  return m;
}

}  // namespace omnislam::runtime
