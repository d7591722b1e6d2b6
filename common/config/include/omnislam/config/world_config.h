// Loading a world file (docs/user/world-file.md) into the pure sim::World description.
#pragma once

#include <string>

#include "omnislam/config/yaml_node.h"
#include "omnislam/sim/world.h"

namespace omnislam::config {

/// Parses and validates a world; throws ConfigError naming the key and the accepted range.
sim::World parseWorld(const Node& root);
/// Loads and parses a world file.
sim::World loadWorld(const std::string& path);

}  // namespace omnislam::config
