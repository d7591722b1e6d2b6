// Fuzz entry points of the YAML configs, parsed and validated as the processes do at start: the SLAM
// config (omnislam-slam), world files (omnislam-sim, -capture, -odometry), the features config and
// the detector it builds (omnislam-features), and launch files (omnislam-launch).
#include <map>
#include <string>

#include "detectors.h"
#include "entry_points.h"
#include "guard.h"
#include "launcher.h"
#include "omnislam/runtime/slam_config.h"
#include "omnislam/config/world_config.h"
#include "omnislam/config/yaml_node.h"

namespace omnislam::fuzz {
namespace {

std::string text(const uint8_t* data, size_t size) { return std::string(reinterpret_cast<const char*>(data), size); }

}  // namespace

void fuzzSlamConfig(const uint8_t* data, size_t size) {
  guard<config::ConfigError>("slam_config", [&] {
    const auto root = config::Node::loadString(text(data, size), "fuzz-slam.yaml");
    (void)runtime::describe(runtime::parseSlamOptions(root));  // echoed at start
  });
}

void fuzzWorldConfig(const uint8_t* data, size_t size) {
  guard<config::ConfigError>(
      "world_config", [&] { (void)config::parseWorld(config::Node::loadString(text(data, size), "fuzz-world.yaml")); });
}

void fuzzFeaturesConfig(const uint8_t* data, size_t size) {
  // Named as a file of config/features/, so that the seeds' relative camera and mask files resolve.
  const std::string source = std::string(OMNISLAM_SOURCE_DIR) + "/config/features/fuzz.yaml";
  guard<config::ConfigError>("features_config", [&] {
    const auto detector = features::makeDetector(config::Node::loadString(text(data, size), source));
    (void)detector->describe();
  });
}

void fuzzLaunchFile(const uint8_t* data, size_t size) {
  const std::string path = scratchFile("launch_file", data, size);
  // --set k=v overrides are the user's own; the file's ${var} substitution throws invalid_argument.
  guard<config::ConfigError, std::invalid_argument>("launch_file",
                                                    [&] { (void)launch::loadPlan(path, {}, "", "", "", false); });
}

}  // namespace omnislam::fuzz
