// The options table of PairingOptions (keys `pairing.*` of a SLAM config): per field its key,
// member, unit, accepted range and meaning (omnislam/core/options_field.h). The key is in seconds
// where the member is in microseconds, in deg/s where it is in rad/s. PairingOptions::validate(),
// the YAML parser (common/config), the start-up echo and the docs table all read it.
#pragma once

#include <vector>

#include "omnislam/core/options_field.h"
#include "omnislam/runtime/pairing.h"

namespace omnislam::runtime {

/// Keys `pairing.*`, in the order the docs and the echo list them.
const std::vector<options::Field<PairingOptions>>& pairingFields();

}  // namespace omnislam::runtime
