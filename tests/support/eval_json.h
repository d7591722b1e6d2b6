// Reading one number out of omnislam-eval's --json output in tests (the keys are documented in
// docs/user/evaluation.md); NaN when the key is absent, so a comparison with it fails.
#pragma once

#include <cmath>
#include <regex>
#include <string>

namespace omnislam::testing {

inline double jsonNumber(const std::string& json, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex("\"" + key + "\": ([-0-9.eE+]+)"))) return NAN;
  return std::stod(m[1]);
}

}  // namespace omnislam::testing
