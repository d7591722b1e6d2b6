// Wheel-data CSV parsing: see csv_source.h.
#include "csv_source.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <stdexcept>

namespace omnislam::odometry {

namespace {

/// The text with every line ending "\n": "\r\n" and a lone "\r" (old Mac files), which getline
/// alone reads as one line, become "\n".
std::string unixLineEnds(const std::string& text) {
  std::string lines = text;
  for (size_t i = 0; i < lines.size(); ++i)
    if (lines[i] == '\r' && (i + 1 == lines.size() || lines[i + 1] != '\n')) lines[i] = '\n';
  return lines;
}

/// One data row as a sample, or the reason it is refused (the caller adds file and line).
WheelSample parseRow(const std::string& line, const std::function<void(const std::string&)>& fail) {
  // Columns are counted by their commas: a trailing comma ("1000,0.1,0.0,") is a fourth, empty
  // column, which reading three fields and looking for more let through.
  const auto columns = std::count(line.begin(), line.end(), ',') + 1;
  if (columns != 3)
    fail("expected 3 columns (utime,v_mps,omega_radps), got " + std::to_string(columns) + " in '" + line + "'");
  std::istringstream row(line);
  std::string f[3];
  for (auto& field : f) std::getline(row, field, ',');
  WheelSample s;
  try {
    size_t pos = 0;
    s.utime = std::stoll(f[0], &pos);
    if (pos != f[0].size()) throw std::invalid_argument("");
    s.v_mps = std::stod(f[1], &pos);
    if (pos != f[1].size()) throw std::invalid_argument("");
    s.omega_radps = std::stod(f[2], &pos);
    if (pos != f[2].size()) throw std::invalid_argument("");
  } catch (const std::exception&) {
    fail("non-numeric field in '" + line + "'");
  }
  if (!std::isfinite(s.v_mps) || !std::isfinite(s.omega_radps)) fail("non-finite value in '" + line + "'");
  if (std::abs(s.v_mps) > kMaxCsvSpeedMps || std::abs(s.omega_radps) > kMaxCsvTurnRateRadps)
    fail("v_mps must be in [-100, 100] and omega_radps in [-100, 100], got '" + line + "'");
  // The contract's utime is >= 0; the bound (year 2096) keeps every difference and sum exact.
  if (s.utime < 0 || s.utime > kMaxCsvUtime)
    fail("utime " + std::to_string(s.utime) + " outside 0.." + std::to_string(kMaxCsvUtime));
  return s;
}

}  // namespace

std::vector<WheelSample> parseWheelCsv(const std::string& text, const std::string& source) {
  std::vector<WheelSample> out;
  std::istringstream in(unixLineEnds(text));
  std::string line;
  int lineno = 0;
  bool header = false;
  const std::function<void(const std::string&)> fail = [&](const std::string& why) {
    throw std::invalid_argument(source + ":" + std::to_string(lineno) + ": " + why);
  };
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    // A UTF-8 byte-order mark, as some spreadsheet programs write, is not part of the header.
    if (lineno == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    if (line.empty() || line[0] == '#') continue;
    if (!header) {
      if (line != "utime,v_mps,omega_radps") fail("expected the header 'utime,v_mps,omega_radps', got '" + line + "'");
      header = true;
      continue;
    }
    const WheelSample s = parseRow(line, fail);
    if (!out.empty() && s.utime <= out.back().utime)
      fail("utime " + std::to_string(s.utime) + " does not increase (previous " + std::to_string(out.back().utime) +
           ")");
    out.push_back(s);
  }
  if (!header) throw std::invalid_argument(source + ": empty file (no header 'utime,v_mps,omega_radps')");
  if (out.empty()) throw std::invalid_argument(source + ": no data rows");
  return out;
}

}  // namespace omnislam::odometry
