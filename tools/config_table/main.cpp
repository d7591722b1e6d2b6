// omnislam-config-table: prints the SLAM filter's config keys as the Markdown table of
// docs/slam-process.md, generated from the options tables (scripts/check-config-docs.py compares).
#include <iostream>

#include "omnislam/config/slam_config.h"

int main() {
  std::cout << omnislam::slamproc::filterKeysMarkdown();
  return 0;
}
