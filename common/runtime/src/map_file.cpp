// Saved maps: YAML text, atomic writes (see map_file.h).
#include "omnislam/runtime/map_file.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
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

/// The first line mapToYaml writes.
constexpr const char* kFirstLine =
    "# omnislam saved map: the best particle's landmarks in the map frame W (metres, m^2).\n";
/// The last line of a version 2 file, newline included: a file cut anywhere lacks it whole.
constexpr const char* kEndLine = "end: omnislam-map\n";

/// Whether the file's last bytes are kEndLine (a YAML parser accepts the file cut before its last
/// newline, or cut inside a landmark's line, so the text itself is checked).
bool endsWithEndLine(const std::string& path) {
  const std::string tail = kEndLine;
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  const std::streamoff size = in ? static_cast<std::streamoff>(in.tellg()) : -1;
  if (size < static_cast<std::streamoff>(tail.size()) + 1) return false;  // + the newline before it
  std::string last(tail.size() + 1, '\0');
  in.seekg(size - static_cast<std::streamoff>(last.size()));
  in.read(last.data(), static_cast<std::streamsize>(last.size()));
  return in && last == "\n" + tail;
}

slam::Landmark readLandmark(const config::Node& n) {
  using config::ConfigError;
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
  return L;
}

/// Whether a refused file may be a version 2 map cut short: empty, or starting as mapToYaml's text
/// starts (its first line, or a `format: omnislam-map` line), without a line "version: 1" (version 1
/// has no end line) and without the end line. Not said of a missing file or a foreign one.
bool mayBeCutShort(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string first = kFirstLine;
  const std::size_t n = std::min(text.size(), first.size());
  const bool starts_as_map = text.compare(0, n, first, 0, n) == 0 || text.rfind("format: omnislam-map", 0) == 0;
  return starts_as_map && text.find("\nversion: 1") == std::string::npos && !endsWithEndLine(path);
}

/// Version 2's count and end marker: a file cut short, or with landmarks lost, is refused.
void checkComplete(const config::Node& root, const std::string& path, std::size_t items) {
  using config::ConfigError;
  const std::string why = " (the file is truncated: cut short while written or copied)";
  if (!root.has("end") || !endsWithEndLine(path))
    throw ConfigError(path + ": a version 2 map must end with the line 'end: omnislam-map'" + why);
  root.getEnum("end", {"omnislam-map"});
  if (!root.has("num_landmarks"))
    throw ConfigError(root.where("num_landmarks") + " is missing: a version 2 map states its landmark count");
  const auto n = static_cast<std::size_t>(root.getInt("num_landmarks", 0, INT64_MAX));
  if (n != items)
    throw ConfigError(root.where("num_landmarks") + " says " + std::to_string(n) + " landmarks, the file holds " +
                      std::to_string(items) + why);
}

}  // namespace

std::string mapToYaml(const SavedMap& map) {
  std::ostringstream o;
  o << kFirstLine
    << "# Written by omnislam-slam; load with --load-map (format: "
       "common/runtime/include/omnislam/runtime/map_file.h).\n"
    << "format: omnislam-map\nversion: 2\nutime: " << map.utime << "\nnum_landmarks: " << map.landmarks.size()
    << "\nlandmarks:";
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
  o << kEndLine;
  return o.str();
}

void saveMapAtomically(const SavedMap& map, const std::string& path) {
  const std::string text = mapToYaml(map);
  writeFileAtomically(path, text.data(), text.size());
}

namespace {

SavedMap loadMapChecked(const std::string& path) {
  using config::ConfigError;
  const config::Node root = config::Node::loadFile(path);
  root.getEnum("format", {"omnislam-map"});
  const int64_t version = root.getInt("version", 1, 2);
  if (version == 1) root.rejectUnknownKeys({"format", "version", "utime", "landmarks"});
  else root.rejectUnknownKeys({"format", "version", "utime", "num_landmarks", "landmarks", "end"});
  SavedMap m;
  m.utime = root.getInt("utime", INT64_MIN, INT64_MAX, 0);
  const std::vector<config::Node> items = root.items("landmarks");
  // The map is published as SLAM_MAP, which carries at most 100 000 landmarks (lcmio::Limits).
  if (items.size() > kMaxSavedLandmarks)
    throw ConfigError(root.where("landmarks") + " holds " + std::to_string(items.size()) + " landmarks, more than " +
                      std::to_string(kMaxSavedLandmarks) + " (the most a map message carries)");
  if (version == 2) checkComplete(root, path, items.size());
  std::unordered_set<std::uint64_t> ids;  // a linear scan per landmark took 10 s for 20 000 under ASan
  for (const config::Node& n : items) {
    slam::Landmark L = readLandmark(n);
    if (!ids.insert(L.id).second) throw ConfigError(n.where("id") + ": duplicate landmark id " + std::to_string(L.id));
    m.landmarks.push_back(L);
  }
  return m;
}

}  // namespace

SavedMap loadMap(const std::string& path) {
  try {
    return loadMapChecked(path);
  } catch (const config::ConfigError& e) {
    // A refusal of a file without the end line (not a version 1 map) says it may be cut short: a
    // cut inside the header breaks a key before the end line is looked for.
    const std::string what = e.what();
    if (what.find("truncated") != std::string::npos || !mayBeCutShort(path)) throw;
    throw config::ConfigError(what +
                              " (the file does not end with the line 'end: omnislam-map' of a version 2 "
                              "map: truncated?)");
  }
}

}  // namespace omnislam::runtime
