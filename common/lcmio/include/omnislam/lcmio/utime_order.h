// The time-order rule of every input of lcmio::Node under lcmio's names: the one implementation is
// omnislam/core/utime_order.h (shared with the SLAM pairing, which is not an LCM component).
#pragma once

#include "omnislam/core/utime_order.h"

namespace omnislam::lcmio {

using omnislam::TimeStep;
using omnislam::UtimeOrder;
using omnislam::UtimeOrderOptions;

}  // namespace omnislam::lcmio
