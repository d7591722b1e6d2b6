// Sizes shared by the message contract and the files that feed it, in one place: the landmarks of
// one map (a SLAM_MAP or GROUND_TRUTH_MAP message, lcmio::Limits), and so of a world file's lights,
// a saved map file and an imported MRCLAM map, each of which becomes such a message.
#pragma once

namespace omnislam {

/// The most landmarks one map may hold.
inline constexpr int kMaxMapLandmarks = 100000;

}  // namespace omnislam
