// The top-level values of an OpenCV FileStorage calibration file that calibration_files.cpp reads:
// the YAML dialect ("%YAML:1.0", !!opencv-matrix) through the project's hardened yaml-cpp loader
// (config::Node::loadString: one document, nesting and alias limits), the XML one through pugixml.
//
// Why not cv::FileStorage: Debian's OpenCV 4.6 parsers fail on short malformed files in ways that
// cannot be caught. Its YAML parser never returns on 18 bytes ("%YAML:1.\n a:]\ni:\n-"); its XML
// parser dereferences a null pointer on the 8 bytes "<?xml n=" (both found by tests/fuzz, kept in
// regressions/calibration). yaml-cpp and pugixml read every file OpenCV writes: its YAML is YAML with
// a nonstandard first line (blanked before parsing, so that line numbers stay right), its XML is XML.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace omnislam::vision::detail {

/// A number ("xi: 0.96"); `whole` when it was written as an integer ("image_width: 1280").
struct OpencvNumber {
  double value = 0.0;
  bool whole = false;
};

/// An !!opencv-matrix (rows, cols, dt, data). `values` (row-major, channels interleaved) is read only
/// when the declared size is small (kMaxMatrixValues): the shape is checked before any allocation.
struct OpencvMatrix {
  int64_t rows = 0, cols = 0;
  int channels = 1;
  std::vector<double> values;
};

/// Anything else (a string, a list, a map that is not a matrix, a matrix whose data does not parse):
/// `what` says which, for messages ("a string", "not an OpenCV matrix: ...").
struct OpencvOther {
  std::string what;
};

/// A key that is absent.
struct OpencvMissing {};

using OpencvValue = std::variant<OpencvMissing, OpencvNumber, OpencvMatrix, OpencvOther>;

/// The values of the keys a calibration reader asks for, by key.
using OpencvValues = std::map<std::string, OpencvValue>;

/// Matrices larger than this are not read (a calibration's largest is the 3x3 camera matrix).
constexpr int64_t kMaxMatrixValues = 64;

/// The text on one line (OpenCV's and yaml-cpp's messages span several), trailing spaces cut.
inline std::string oneLine(std::string s) {
  for (char& ch : s)
    if (ch == '\n' || ch == '\r') ch = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

/// The keys the calibration readers use.
const std::vector<std::string>& opencvCalibrationKeys();

/// Reads `keys` from an OpenCV FileStorage file's text (YAML or XML, told by its first line).
/// Throws config::ConfigError "'source': not a readable OpenCV FileStorage file: why" when the file
/// does not parse or its top level is not a map.
OpencvValues readOpencvValues(const std::string& text, const std::string& source, const std::vector<std::string>& keys);

}  // namespace omnislam::vision::detail
