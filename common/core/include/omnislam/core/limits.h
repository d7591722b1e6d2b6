// Sizes shared by the message contract and the files that feed it, in one place: the landmarks of
// one map (a SLAM_MAP or GROUND_TRUTH_MAP message, lcmio::Limits), and so of a world file's lights,
// a saved map file and an imported MRCLAM map, each of which becomes such a message; the largest
// utime a message (and so a checkpoint's state taken from messages) may carry.
#pragma once

#include <cstdint>

namespace omnislam {

/// The largest utime accepted (2^62 us, some 146 000 years after 1970). Anything later is a
/// corrupted field, and the bound leaves every receiver room to add a duration to a utime
/// without overflowing int64 (a restart window, a buffer length).
inline constexpr std::int64_t kMaxUtime = std::int64_t{1} << 62;

/// The most landmarks one map may hold.
inline constexpr int kMaxMapLandmarks = 100000;

}  // namespace omnislam
