// Parsing the text files of the UTIAS MRCLAM datasets (Leung et al., IJRR 2011): RobotN_Odometry,
// RobotN_Measurement, RobotN_Groundtruth, Landmark_Groundtruth, Barcodes. Comment lines start with
// '#'; data lines hold whitespace-separated numbers. Every malformed line is an error naming the
// file and the line (missing or extra columns, non-numeric or non-finite fields, values beyond the
// physical bounds below, non-integral ids, times going back or repeated, an empty file); nothing is
// dropped silently: what a policy lets
// through is counted in FileStats. Units as in the files: seconds, metres, radians. No LCM here.
#pragma once

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "omnislam/core/limits.h"

namespace omnislam::mrclam {

/// A malformed or unreadable input file; what() is "FILE:LINE: reason" (or "FILE: reason").
struct ParseError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Largest time a row may have [s since the Unix epoch]: 4e9 s (the year 2096) is 4e15 us, the
/// bound of utimes elsewhere; MRCLAM's times are about 1.25e9 s.
constexpr double kMaxTimeS = 4e9;

/// Physical bounds on the values of a data line (beyond them a line is refused, naming the file, the
/// line, the column and the range): MRCLAM's robots drive below 0.1 m/s and 0.6 rad/s in a 10 m
/// arena, so each bound is orders of magnitude away from real data. They keep every integrated
/// pose, covariance and distance the importer and the evaluation compute finite.
constexpr double kMaxSpeedMps = 100.0;        ///< |forward velocity|
constexpr double kMaxTurnRateRadps = 100.0;   ///< |angular velocity|
constexpr double kMaxCoordinateM = 1e6;       ///< |x|, |y| of a truth pose or a landmark
constexpr double kMaxAngleRad = 100.0;        ///< |orientation|, |bearing| (wrapped afterwards)
constexpr double kMaxRangeM = 1e6;            ///< range in 0..kMaxRangeM (read, then dropped)
constexpr double kMaxLandmarkSigmaM = 100.0;  ///< landmark std-dev in 0..kMaxLandmarkSigmaM
/// The message contract's sizes (lcmio::Limits; the first checked at compile time by the
/// importer): more measurements at one time than a frame may carry, or more landmarks than a map,
/// are refused.
constexpr int kMaxMeasurementsPerTime = 4096;
constexpr int kMaxLandmarks = kMaxMapLandmarks;

/// A file's time [s] as the messages' utime [us], rounded to the nearest microsecond.
inline int64_t toUtime(double t_s) { return static_cast<int64_t>(std::llround(t_s * 1e6)); }

/// What to do with a data line whose time equals the previous line's (odometry, ground truth).
enum class DuplicateTimes {
  kError,     ///< refuse the file (the default)
  kKeepLast,  ///< the later line replaces the earlier one; counted in FileStats::duplicates_replaced
};

struct FileStats {
  std::string path;
  int64_t lines = 0;                     ///< all lines read
  int64_t comment_lines = 0;             ///< lines starting with '#'
  int64_t blank_lines = 0;               ///< empty or whitespace-only lines
  int64_t data_lines = 0;                ///< lines parsed as data
  int64_t duplicates_replaced = 0;       ///< data lines replaced by a later line with the same time
  std::vector<int64_t> duplicate_lines;  ///< line numbers (1-based) of the replacing lines
};

/// Rows of numbers, each with its 1-based line number in the file.
struct Table {
  FileStats stats;
  std::vector<std::vector<double>> rows;
  std::vector<int64_t> line_of_row;
};

/// Reads a table with exactly column_names.size() numeric, finite columns per data line.
Table readTable(const std::string& path, const std::vector<std::string>& column_names);

struct OdometrySample {
  double t_s = 0.0;
  double v_mps = 0.0;
  double omega_radps = 0.0;
};
struct PoseSample {
  double t_s = 0.0;
  double x_m = 0.0, y_m = 0.0, theta_rad = 0.0;
};
struct Measurement {
  double t_s = 0.0;
  int code = 0;  ///< the barcode read (the files' "Subject #" column holds barcodes)
  double range_m = 0.0;
  double bearing_rad = 0.0;
  int64_t line = 0;
};
struct LandmarkTruth {
  int subject = 0;
  double x_m = 0.0, y_m = 0.0;
  double x_sigma_m = 0.0, y_sigma_m = 0.0;
};
struct BarcodeEntry {
  int subject = 0;
  int barcode = 0;
};

/// Times strictly increasing (a repeated time per `dup`); the first data line's time is the start.
std::vector<OdometrySample> readOdometry(const std::string& path, DuplicateTimes dup, FileStats* stats = nullptr);
std::vector<PoseSample> readGroundtruth(const std::string& path, DuplicateTimes dup, FileStats* stats = nullptr);
/// Times non-decreasing (equal times = one frame, at most kMaxMeasurementsPerTime rows); the code
/// column must be integral.
std::vector<Measurement> readMeasurements(const std::string& path, FileStats* stats = nullptr);
/// Subjects integral and unique.
std::vector<LandmarkTruth> readLandmarks(const std::string& path, FileStats* stats = nullptr);
/// Subjects and barcodes integral and unique.
std::vector<BarcodeEntry> readBarcodes(const std::string& path, FileStats* stats = nullptr);

/// "FILE: N lines (C comments, B blank, D data), R duplicated times replaced (lines ...)".
std::string describe(const FileStats& s);

}  // namespace omnislam::mrclam
