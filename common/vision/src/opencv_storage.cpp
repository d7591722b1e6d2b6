// Reading an OpenCV FileStorage calibration file's top-level values: see opencv_storage.h.
#include "opencv_storage.h"

#include <pugixml.hpp>
#include <yaml-cpp/yaml.h>

#include <cctype>
#include <charconv>
#include <cstdlib>
#include <sstream>

#include "omnislam/config/yaml_node.h"

namespace omnislam::vision::detail {
namespace {

using config::ConfigError;

[[noreturn]] void unreadable(const std::string& source, const std::string& why) {
  throw ConfigError("'" + source + "': not a readable OpenCV FileStorage file: " + oneLine(why));
}

/// An integer written as one ("1280", "-3"), else nullopt ("1280.0", "1e3", "x").
std::optional<int64_t> wholeNumber(const std::string& s) {
  int64_t v = 0;
  const char* first = s.data() + (!s.empty() && s[0] == '+');
  const char* last = s.data() + s.size();
  const auto [end, ec] = std::from_chars(first, last, v);
  if (ec != std::errc() || end != last || first == last) return std::nullopt;
  return v;
}

/// The channel count of an OpenCV element type ("d" -> 1, "3f" -> 3); 0 when it is not one.
int channelsOf(const std::string& dt) {
  size_t i = 0;
  int64_t n = 0;
  while (i < dt.size() && std::isdigit(static_cast<unsigned char>(dt[i])) && n <= 512) n = 10 * n + (dt[i++] - '0');
  if (i == dt.size() || n > 512) return 0;  // no element letter, or absurd
  return i == 0 ? 1 : static_cast<int>(n);
}

/// Whether a declared rows x cols x channels is small enough to read (kMaxMatrixValues).
bool smallEnough(int64_t rows, int64_t cols, int channels) {
  return rows >= 0 && cols >= 0 && rows <= kMaxMatrixValues && cols <= kMaxMatrixValues &&
         rows * cols * channels <= kMaxMatrixValues;
}

// ---- YAML, through yaml-cpp ----

/// The text with its "%YAML:1.0" (or "%YAML 1.0") line blanked: yaml-cpp does not know OpenCV's form.
std::string blankDirective(const std::string& text) {
  std::string t = text;
  size_t p = t.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
  p = t.find_first_not_of(" \t\r\n", p);
  if (p != std::string::npos && t.compare(p, 5, "%YAML") == 0)
    for (; p < t.size() && t[p] != '\n' && t[p] != '\r'; ++p) t[p] = ' ';
  return t;
}

OpencvValue yamlMatrix(const YAML::Node& n) {
  OpencvMatrix m;
  const auto rows = n["rows"].IsScalar() ? wholeNumber(n["rows"].Scalar()) : std::nullopt;
  const auto cols = n["cols"].IsScalar() ? wholeNumber(n["cols"].Scalar()) : std::nullopt;
  m.channels = n["dt"] ? (n["dt"].IsScalar() ? channelsOf(n["dt"].Scalar()) : 0) : 1;
  if (!rows || !cols || m.channels == 0)
    return OpencvOther{"not an OpenCV matrix: rows and cols must be whole numbers and dt an element type"};
  m.rows = *rows;
  m.cols = *cols;
  if (!smallEnough(m.rows, m.cols, m.channels)) return m;  // the shape check refuses it, naming the shape
  const YAML::Node data = n["data"];
  const size_t want = static_cast<size_t>(m.rows * m.cols * m.channels);
  if (!data.IsSequence() || data.size() != want)
    return OpencvOther{"not an OpenCV matrix: its data must be a list of rows x cols x channels = " +
                       std::to_string(want) + " numbers"};
  for (const YAML::Node& v : data) {
    try {
      if (!v.IsScalar()) throw YAML::BadConversion(v.Mark());
      m.values.push_back(v.as<double>());
    } catch (const YAML::Exception&) {
      return OpencvOther{"not an OpenCV matrix: its data holds something that is not a number"};
    }
  }
  return m;
}

OpencvValue yamlValue(const YAML::Node& n) {
  if (!n) return OpencvMissing{};
  if (n.IsNull()) return OpencvOther{"empty"};
  if (n.IsSequence()) return OpencvOther{"a list"};
  if (n.IsMap()) {
    if (n["rows"] && n["cols"] && n["data"]) return yamlMatrix(n);
    return OpencvOther{"a map that is not an OpenCV matrix (rows, cols, dt, data)"};
  }
  if (const auto w = wholeNumber(n.Scalar())) return OpencvNumber{static_cast<double>(*w), true};
  try {
    return OpencvNumber{n.as<double>(), false};
  } catch (const YAML::Exception&) {
    return OpencvOther{"a string"};
  }
}

OpencvValues readYaml(const std::string& text, const std::string& source, const std::vector<std::string>& keys) {
  const std::string yaml = blankDirective(text);
  try {
    (void)config::Node::loadString(yaml, source);  // one document, a map, no repeated keys or map aliases
  } catch (const ConfigError& e) {
    const std::string m = e.what(), prefix = source + ": ";
    unreadable(source, m.compare(0, prefix.size(), prefix) == 0 ? m.substr(prefix.size()) : m);
  }
  OpencvValues out;
  try {
    const YAML::Node root = YAML::Load(yaml);
    for (const std::string& k : keys) out[k] = yamlValue(root[k]);
  } catch (const YAML::Exception& e) {
    unreadable(source, e.what());
  }
  return out;
}

// ---- XML, through pugixml ----

/// The whitespace-separated words of an element's text.
std::vector<std::string> words(const char* text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

/// A number written as a whole word ("1.", "-3e-2", "nan"), else nullopt.
std::optional<double> realNumber(const std::string& w) {
  if (w.empty() || std::isspace(static_cast<unsigned char>(w[0]))) return std::nullopt;
  char* end = nullptr;
  const double v = std::strtod(w.c_str(), &end);
  if (end != w.c_str() + w.size()) return std::nullopt;
  return v;
}

OpencvValue xmlMatrix(const pugi::xml_node& n) {
  const auto rows = wholeNumber(n.child("rows").text().as_string());
  const auto cols = wholeNumber(n.child("cols").text().as_string());
  OpencvMatrix m;
  const std::vector<std::string> dt = words(n.child("dt").text().as_string());
  m.channels = dt.size() == 1 ? channelsOf(dt[0]) : 0;
  if (!rows || !cols || m.channels == 0)
    return OpencvOther{"not an OpenCV matrix: rows and cols must be whole numbers and dt an element type"};
  m.rows = *rows;
  m.cols = *cols;
  if (!smallEnough(m.rows, m.cols, m.channels)) return m;  // the shape check refuses it, naming the shape
  const std::vector<std::string> data = words(n.child("data").text().as_string());
  const size_t want = static_cast<size_t>(m.rows * m.cols * m.channels);
  if (data.size() != want)
    return OpencvOther{"not an OpenCV matrix: its data must be a list of rows x cols x channels = " +
                       std::to_string(want) + " numbers"};
  for (const std::string& w : data) {
    const auto v = realNumber(w);
    if (!v) return OpencvOther{"not an OpenCV matrix: its data holds something that is not a number"};
    m.values.push_back(*v);
  }
  return m;
}

OpencvValue xmlValue(const pugi::xml_node& n) {
  if (!n) return OpencvMissing{};
  if (std::string(n.attribute("type_id").as_string()) == "opencv-matrix") return xmlMatrix(n);
  if (n.first_child() && n.first_child().type() == pugi::node_element)
    return OpencvOther{"a map that is not an OpenCV matrix (rows, cols, dt, data)"};
  const std::vector<std::string> w = words(n.text().as_string());
  if (w.empty()) return OpencvOther{"empty"};
  if (w.size() > 1) return OpencvOther{"a list"};
  if (const auto i = wholeNumber(w[0])) return OpencvNumber{static_cast<double>(*i), true};
  if (const auto v = realNumber(w[0])) return OpencvNumber{*v, false};
  return OpencvOther{"a string"};
}

OpencvValues readXml(const std::string& text, const std::string& source, const std::vector<std::string>& keys) {
  pugi::xml_document doc;
  const pugi::xml_parse_result r = doc.load_buffer(text.data(), text.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!r) unreadable(source, std::string("not valid XML: ") + r.description() + " at byte " + std::to_string(r.offset));
  const pugi::xml_node root = doc.child("opencv_storage");
  if (!root) unreadable(source, "its XML root element must be <opencv_storage>");
  OpencvValues out;
  for (const std::string& k : keys) {
    const pugi::xml_node n = root.child(k.c_str());
    if (n && n.next_sibling(k.c_str())) unreadable(source, "key '" + k + "' is given twice; give it once");
    out[k] = xmlValue(n);
  }
  return out;
}

}  // namespace

const std::vector<std::string>& opencvCalibrationKeys() {
  static const std::vector<std::string> keys = {"camera_matrix", "distortion_coefficients", "xi", "image_width",
                                                "image_height"};
  return keys;
}

OpencvValues readOpencvValues(const std::string& text, const std::string& source,
                              const std::vector<std::string>& keys) {
  const size_t p = text.find_first_not_of(" \t\r\n", text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0);
  const bool xml = p != std::string::npos && text.compare(p, 5, "<?xml") == 0;
  return xml ? readXml(text, source, keys) : readYaml(text, source, keys);
}

}  // namespace omnislam::vision::detail
