// Parsing the MRCLAM text files: see mrclam_files.h.
#include "mrclam_files.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

namespace omnislam::mrclam {
namespace {

std::string at(const std::string& path, int64_t line) { return path + ":" + std::to_string(line) + ": "; }

std::string fmtTime(double t) {
  std::ostringstream s;
  s.precision(15);
  s << t;
  return s.str();
}

/// Throws unless the row's time is in 0..kMaxTimeS (beyond it, or NaN, it has no utime).
void checkTimeRange(const std::string& path, int64_t line, double t_s) {
  if (!(t_s >= 0.0 && t_s <= kMaxTimeS))
    throw ParseError(at(path, line) + "time " + fmtTime(t_s) + " s outside 0.." + fmtTime(kMaxTimeS) + " s");
}

int integral(const std::string& path, int64_t line, const std::string& name, double v) {
  if (v != std::floor(v) || std::abs(v) > 1e9)
    throw ParseError(at(path, line) + "column '" + name + "' must be an integer, got " + fmtTime(v));
  return static_cast<int>(v);
}

/// Strictly increasing times in column 0, in 0..kMaxTimeS; a repeated time is an error or replaces
/// the earlier row. Order and repeats are judged on the microseconds the messages will carry: two
/// times 0.2 us apart are one utime.
void checkTimes(Table& t, DuplicateTimes dup) {
  std::vector<std::vector<double>> rows;
  std::vector<int64_t> lines;
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const double t_s = t.rows[i][0];
    checkTimeRange(t.stats.path, t.line_of_row[i], t_s);
    if (!rows.empty()) {
      const double prev = rows.back()[0], now = t_s;
      if (toUtime(now) < toUtime(prev))
        throw ParseError(at(t.stats.path, t.line_of_row[i]) + "time " + fmtTime(now) + " s is before the previous (" +
                         fmtTime(prev) + " s at line " + std::to_string(lines.back()) + "): times must increase");
      if (toUtime(now) == toUtime(prev)) {
        if (dup == DuplicateTimes::kError)
          throw ParseError(at(t.stats.path, t.line_of_row[i]) + "duplicated time " + fmtTime(now) +
                           " s (same as line " + std::to_string(lines.back()) +
                           "); --duplicate-times keep-last keeps the later line");
        rows.back() = t.rows[i];
        lines.back() = t.line_of_row[i];
        ++t.stats.duplicates_replaced;
        t.stats.duplicate_lines.push_back(t.line_of_row[i]);
        continue;
      }
    }
    rows.push_back(t.rows[i]);
    lines.push_back(t.line_of_row[i]);
  }
  t.rows = std::move(rows);
  t.line_of_row = std::move(lines);
}

/// Throws unless lo <= v <= hi, naming the column and the accepted range.
void checkValue(const std::string& path, int64_t line, const std::string& name, double v, double lo, double hi) {
  if (!(v >= lo && v <= hi))
    throw ParseError(at(path, line) + "column '" + name + "' is " + fmtTime(v) + ", outside " + fmtTime(lo) + ".." +
                     fmtTime(hi));
}

/// One line, ended by "\n", "\r\n" or a lone "\r" (old Mac files: std::getline read such a file
/// as one line, its first comment hiding every data line). False at the end of the input.
bool readLine(std::istream& in, std::string& line) {
  line.clear();
  std::streambuf* sb = in.rdbuf();
  for (;;) {
    const int c = sb->sbumpc();
    if (c == std::char_traits<char>::eof()) {
      if (line.empty()) in.setstate(std::ios::eofbit);
      return !line.empty();
    }
    if (c == '\n') return true;
    if (c == '\r') {
      if (sb->sgetc() == '\n') sb->sbumpc();
      return true;
    }
    line.push_back(static_cast<char>(c));
  }
}

void put(FileStats* out, const FileStats& s) {
  if (out) *out = s;
}

}  // namespace

Table readTable(const std::string& path, const std::vector<std::string>& names) {
  std::ifstream f(path);
  if (!f) throw ParseError(path + ": cannot open file");
  Table t;
  t.stats.path = path;
  std::string line;
  int64_t n = 0;
  while (readLine(f, line)) {
    ++n;
    if (n == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // a UTF-8 byte-order mark
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos) {
      ++t.stats.blank_lines;
      continue;
    }
    if (line[first] == '#') {
      ++t.stats.comment_lines;
      continue;
    }
    std::istringstream in(line);
    std::vector<double> row;
    std::string tok;
    while (in >> tok) {
      if (row.size() == names.size())
        throw ParseError(at(path, n) + "extra column '" + tok + "' (expected " + std::to_string(names.size()) +
                         " columns)");
      errno = 0;
      char* end = nullptr;
      const double v = std::strtod(tok.c_str(), &end);
      const std::string& name = names[row.size()];
      if (end == tok.c_str() || *end != '\0' || errno == ERANGE)
        throw ParseError(at(path, n) + "column " + std::to_string(row.size() + 1) + " '" + name +
                         "' is not a number: '" + tok + "'");
      if (!std::isfinite(v))
        throw ParseError(at(path, n) + "column " + std::to_string(row.size() + 1) + " '" + name + "' is not finite: '" +
                         tok + "'");
      row.push_back(v);
    }
    if (row.size() < names.size())
      throw ParseError(at(path, n) + "missing column " + std::to_string(row.size() + 1) + " '" + names[row.size()] +
                       "' (expected " + std::to_string(names.size()) + " columns, found " + std::to_string(row.size()) +
                       ")");
    t.rows.push_back(std::move(row));
    t.line_of_row.push_back(n);
  }
  if (f.bad()) throw ParseError(path + ": read error");
  t.stats.lines = n;
  t.stats.data_lines = static_cast<int64_t>(t.rows.size());
  if (t.rows.empty()) throw ParseError(path + ": no data lines (empty file)");
  return t;
}

std::vector<OdometrySample> readOdometry(const std::string& path, DuplicateTimes dup, FileStats* stats) {
  Table t = readTable(path, {"time [s]", "forward velocity [m/s]", "angular velocity [rad/s]"});
  checkTimes(t, dup);
  std::vector<OdometrySample> out;
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const auto& r = t.rows[i];
    checkValue(path, t.line_of_row[i], "forward velocity [m/s]", r[1], -kMaxSpeedMps, kMaxSpeedMps);
    checkValue(path, t.line_of_row[i], "angular velocity [rad/s]", r[2], -kMaxTurnRateRadps, kMaxTurnRateRadps);
    out.push_back({r[0], r[1], r[2]});
  }
  put(stats, t.stats);
  return out;
}

std::vector<PoseSample> readGroundtruth(const std::string& path, DuplicateTimes dup, FileStats* stats) {
  Table t = readTable(path, {"time [s]", "x [m]", "y [m]", "orientation [rad]"});
  checkTimes(t, dup);
  std::vector<PoseSample> out;
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const auto& r = t.rows[i];
    checkValue(path, t.line_of_row[i], "x [m]", r[1], -kMaxCoordinateM, kMaxCoordinateM);
    checkValue(path, t.line_of_row[i], "y [m]", r[2], -kMaxCoordinateM, kMaxCoordinateM);
    checkValue(path, t.line_of_row[i], "orientation [rad]", r[3], -kMaxAngleRad, kMaxAngleRad);
    out.push_back({r[0], r[1], r[2], r[3]});
  }
  put(stats, t.stats);
  return out;
}

std::vector<Measurement> readMeasurements(const std::string& path, FileStats* stats) {
  Table t = readTable(path, {"time [s]", "subject (barcode)", "range [m]", "bearing [rad]"});
  std::vector<Measurement> out;
  size_t first_at_time = 0;  // index in out of the first row with the current time
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const auto& r = t.rows[i];
    const int64_t line = t.line_of_row[i];
    checkTimeRange(path, line, r[0]);
    if (!out.empty() && r[0] < out.back().t_s)
      throw ParseError(at(path, line) + "time " + fmtTime(r[0]) + " s is before the previous (" +
                       fmtTime(out.back().t_s) + " s at line " + std::to_string(out.back().line) +
                       "): times must not decrease");
    if (out.empty() || r[0] != out.back().t_s) first_at_time = out.size();
    if (out.size() - first_at_time == static_cast<size_t>(kMaxMeasurementsPerTime))
      throw ParseError(at(path, line) + "more than " + std::to_string(kMaxMeasurementsPerTime) +
                       " measurements at time " + fmtTime(r[0]) + " s (from line " +
                       std::to_string(out[first_at_time].line) + "): one frame carries at most " +
                       std::to_string(kMaxMeasurementsPerTime));
    checkValue(path, line, "range [m]", r[2], 0.0, kMaxRangeM);
    checkValue(path, line, "bearing [rad]", r[3], -kMaxAngleRad, kMaxAngleRad);
    out.push_back({r[0], integral(path, line, "subject (barcode)", r[1]), r[2], r[3], line});
  }
  put(stats, t.stats);
  return out;
}

std::vector<LandmarkTruth> readLandmarks(const std::string& path, FileStats* stats) {
  Table t = readTable(path, {"subject", "x [m]", "y [m]", "x std-dev [m]", "y std-dev [m]"});
  std::vector<LandmarkTruth> out;
  std::set<int> seen;
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const auto& r = t.rows[i];
    const int64_t line = t.line_of_row[i];
    const int s = integral(path, line, "subject", r[0]);
    if (!seen.insert(s).second) throw ParseError(at(path, line) + "duplicated subject " + std::to_string(s));
    if (i == static_cast<size_t>(kMaxLandmarks))
      throw ParseError(at(path, line) + "more than " + std::to_string(kMaxLandmarks) + " landmarks");
    checkValue(path, line, "x [m]", r[1], -kMaxCoordinateM, kMaxCoordinateM);
    checkValue(path, line, "y [m]", r[2], -kMaxCoordinateM, kMaxCoordinateM);
    checkValue(path, line, "x std-dev [m]", r[3], 0.0, kMaxLandmarkSigmaM);
    checkValue(path, line, "y std-dev [m]", r[4], 0.0, kMaxLandmarkSigmaM);
    out.push_back({s, r[1], r[2], r[3], r[4]});
  }
  put(stats, t.stats);
  return out;
}

std::vector<BarcodeEntry> readBarcodes(const std::string& path, FileStats* stats) {
  Table t = readTable(path, {"subject", "barcode"});
  std::vector<BarcodeEntry> out;
  std::set<int> subjects, codes;
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const auto& r = t.rows[i];
    const int64_t line = t.line_of_row[i];
    const int s = integral(path, line, "subject", r[0]);
    const int b = integral(path, line, "barcode", r[1]);
    if (!subjects.insert(s).second) throw ParseError(at(path, line) + "duplicated subject " + std::to_string(s));
    if (!codes.insert(b).second) throw ParseError(at(path, line) + "duplicated barcode " + std::to_string(b));
    out.push_back({s, b});
  }
  put(stats, t.stats);
  return out;
}

std::string describe(const FileStats& s) {
  std::ostringstream o;
  o << s.path << ": " << s.lines << " lines (" << s.comment_lines << " comments, " << s.blank_lines << " blank, "
    << s.data_lines << " data)";
  if (s.duplicates_replaced > 0) {
    o << ", " << s.duplicates_replaced << " duplicated times, the later line kept (lines";
    for (size_t i = 0; i < s.duplicate_lines.size() && i < 10; ++i) o << " " << s.duplicate_lines[i];
    if (s.duplicate_lines.size() > 10) o << " ...";
    o << ")";
  }
  return o.str();
}

}  // namespace omnislam::mrclam
