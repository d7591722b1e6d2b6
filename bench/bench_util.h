// Small helpers shared by the bench programs (not Google Benchmark ones): the machine's load
// average, which the figures are read against, and fixed-precision formatting.
#pragma once

#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>

namespace omnislam::bench {

/// The first line of /proc/loadavg (other work on the machine shows in the wall times).
inline std::string loadAverage() {
  std::ifstream f("/proc/loadavg");
  std::string line;
  std::getline(f, line);
  return line.empty() ? "?" : line;
}

inline std::string fmt(double x, int prec) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(prec) << x;
  return s.str();
}

}  // namespace omnislam::bench
