// One landmark in the byte format of filter checkpoints (filter_state.cpp: id, position, covariance
// row-major, counter, type, kind, descriptor), for the other states that hold a map (lost_monitor.h).
#pragma once

#include "omnislam/core/byte_codec.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::slam {

void putLandmark(ByteWriter& w, const Landmark& l);
/// Throws StateFormatError on a malformed landmark (type, kind).
Landmark getLandmark(ByteReader& r);

}  // namespace omnislam::slam
