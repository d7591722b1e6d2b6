// The SLAM's landmark map as its LCM message (map_t on SLAM_MAP): one conversion for the SLAM
// driver and the research programs that write what omnislam-slam writes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "omnislam/core/slam/types.h"
#include "omnislam/map_t.hpp"

namespace omnislam::runtime {

/// map_t of `landmarks` (position and covariance in W [m, m^2], type I = 1 / II = 2, detection
/// counter, kind) in their order, with the header fields and the number of candidates as given.
map_t toMapMessage(const std::vector<slam::Landmark>& landmarks, std::size_t num_candidates, std::int64_t utime,
                   std::int64_t seq, std::int64_t input_seq);

}  // namespace omnislam::runtime
