// omnislam-config-table: prints the SLAM config's keys as the Markdown tables of
// docs/user/slam-process.md, generated from the options tables (scripts/check-config-docs.py compares).
//   omnislam-config-table filter    the `filter.*` keys
//   omnislam-config-table process   every other key (seed, start_pose.*, features.*, ...)
#include <iostream>
#include <string>

#include "omnislam/config/slam_config.h"

int main(int argc, char** argv) {
  const std::string which = argc == 2 ? argv[1] : "";
  if (which == "filter") {
    std::cout << omnislam::slamproc::filterKeysMarkdown();
  } else if (which == "process") {
    std::cout << omnislam::slamproc::processKeysMarkdown();
  } else {
    std::cerr << "usage: omnislam-config-table filter|process (the keys of docs/user/slam-process.md)\n";
    return 2;
  }
  return 0;
}
