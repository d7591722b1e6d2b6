// Saved maps of the SLAM process: the best particle's landmarks written as YAML (one landmark per
// line, full double precision) and read back as a prior map. Writing is atomic: a temporary file
// in the same folder is written, flushed to disk and renamed over the target, so a reader (or a
// crash, SIGINT or SIGTERM during the write) never sees a half-written map.
// Frame: the map frame W of the run that saved it (docs/user/conventions.md); metres, m^2.
// Format (version 2, written since issue 56):
//   format: omnislam-map
//   version: 2
//   utime: <utime of the frame the map answers, microseconds>
//   num_landmarks: <the count of the list below>
//   landmarks:
//     - {id: 3, kind: point3d|vertical_line, type: 1|2, counter: 7,
//        position_m: [x, y, z], covariance_m2: [c00, c01, c02, c10, ..., c22]}
//   end: omnislam-map          (the last line, its newline included)
// A version 2 file cut at any byte lacks its end line, or its count disagrees: refused, named as
// truncated. Version 1 (no num_landmarks, no end line) still loads; a v1 file cut at a line boundary
// cannot be told from a smaller map.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "omnislam/core/limits.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::runtime {

struct SavedMap {
  int64_t utime = 0;
  std::vector<slam::Landmark> landmarks;
};

/// The YAML text of a map (deterministic: the same map gives the same bytes).
std::string mapToYaml(const SavedMap& map);

/// Writes atomically and durably (writeFileAtomically, atomic_file.h). Throws std::runtime_error
/// naming the path, the step that failed and the system's reason.
void saveMapAtomically(const SavedMap& map, const std::string& path);

/// The most landmarks a map file may hold: what one SLAM_MAP message carries.
inline constexpr std::size_t kMaxSavedLandmarks = kMaxMapLandmarks;

/// Reads a map file (version 1 or 2); a missing file, a wrong format, version, kind, non-finite
/// number, a covariance that is not symmetric positive definite, a repeated id, more than
/// kMaxSavedLandmarks landmarks, or (version 2) a missing end line or a count that disagrees throws
/// config::ConfigError naming the file, the key and the landmark.
SavedMap loadMap(const std::string& path);

}  // namespace omnislam::runtime
