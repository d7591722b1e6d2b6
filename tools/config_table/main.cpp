// omnislam-config-table: prints config keys as the Markdown tables of the docs, generated from the
// options tables (scripts/check-config-docs.py compares them with the pages' generated blocks).
//   omnislam-config-table filter                   the SLAM's `filter.*` keys (docs/user/slam-process.md)
//   omnislam-config-table process                  the SLAM's other keys (seed, start_pose.*, features.*, ...)
//   omnislam-config-table lights                   the features config's `ceiling_lights.*` (docs/design/detectors.md)
//   omnislam-config-table lines                    its `vertical_lines.*`
//   omnislam-config-table world_camera             a world file's Pajdla-Bakstein camera (docs/user/world-file.md)
//   omnislam-config-table world_camera_scaramuzza  a world file's Scaramuzza camera keys with a default
//   omnislam-config-table merge                    omnislam-merge-maps' flags (docs/design/global-localisation.md)
#include <functional>
#include <iostream>
#include <map>
#include <string>

#include "detector_options_table.h"
#include "omnislam/config/options_parse.h"
#include "omnislam/config/world_camera_table.h"
#include "omnislam/core/slam/options_table.h"
#include "omnislam/runtime/slam_config.h"

int main(int argc, char** argv) {
  const std::map<std::string, std::function<std::string()>> tables{
      {"filter", omnislam::runtime::filterKeysMarkdown},
      {"process", omnislam::runtime::processKeysMarkdown},
      {"lights", omnislam::features::lightsKeysMarkdown},
      {"lines", omnislam::features::linesKeysMarkdown},
      {"world_camera", omnislam::config::worldCameraKeysMarkdown},
      {"world_camera_scaramuzza", omnislam::config::worldScaramuzzaKeysMarkdown},
      {"merge",
       [] {
         return omnislam::config::markdownHeader() +
                omnislam::config::markdownRows("--", omnislam::slam::options::mapRegistrationFields(),
                                               omnislam::slam::MapRegistrationOptions{});
       }},
  };
  const auto it = tables.find(argc == 2 ? argv[1] : "");
  if (it == tables.end()) {
    std::cerr
        << "usage: omnislam-config-table filter|process|lights|lines|world_camera|world_camera_scaramuzza|merge\n";
    return 2;
  }
  std::cout << it->second();
  return 0;
}
