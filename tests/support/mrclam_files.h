// Test support: writing small files in the UTIAS MRCLAM format (a 4-line comment header, then the
// data lines), for the importer's tests and the run-mrclam.sh script test.
#pragma once

#include <fstream>
#include <string>

namespace omnislam::testing {

/// The dataset's header: 4 comment lines, as in every MRCLAM .dat file.
inline constexpr const char* kMrclamHeader =
    "# UTIAS Multi-Robot Cooperative Localization and Mapping Dataset\n# test\n# format\n# columns\n";

/// Writes kMrclamHeader and then `body` (the data lines) to `path`.
inline void writeMrclamFile(const std::string& path, const std::string& body) {
  std::ofstream f(path);
  f << kMrclamHeader << body;
}

}  // namespace omnislam::testing
