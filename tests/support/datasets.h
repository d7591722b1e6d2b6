// Test support: where the shared datasets are. $OMNISLAM_DATASETS if set, else ../shared/datasets
// beside the source tree (the layout of a developer's and CI's checkout). Tests that need a file
// skip with a message naming the path when it is absent.
#pragma once

#include <cstdlib>
#include <string>

namespace omnislam::testing {

inline std::string datasetPath(const std::string& rel) {
  const char* env = std::getenv("OMNISLAM_DATASETS");
  const std::string root = env && *env ? std::string(env) : std::string(OMNISLAM_SOURCE_DIR) + "/../shared/datasets";
  return root + "/" + rel;
}

}  // namespace omnislam::testing
