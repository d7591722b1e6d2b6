// Readers of OpenCV / Kalibr / OCamCalib calibration files: see calibration_files.h.
#include "omnislam/vision/calibration_files.h"

#include <opencv2/core.hpp>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>

#include "omnislam/config/yaml_node.h"
#include "omnislam/core/camera/double_sphere.h"
#include "omnislam/core/camera/eucm.h"
#include "omnislam/core/camera/kannala_brandt.h"
#include "omnislam/core/camera/mei.h"
#include "omnislam/core/camera/reflected_camera.h"

namespace omnislam::vision {
namespace {

using config::ConfigError;

const char* const kAccepted =
    "accepted: OpenCV FileStorage YAML/XML of cv::omnidir (camera_matrix, distortion_coefficients, xi) or "
    "cv::fisheye (camera_matrix, distortion_coefficients), Kalibr camchain.yaml (camN.camera_model ...), "
    "OCamCalib calib_results.txt";

[[noreturn]] void fail(const std::string& source, const std::string& what) {
  throw ConfigError("'" + source + "': " + what);
}

std::string oneLine(std::string s) {
  for (char& ch : s)
    if (ch == '\n' || ch == '\r') ch = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

/// The text after a UTF-8 byte-order mark and leading white space.
std::string_view body(const std::string& text) {
  std::string_view t(text);
  if (t.substr(0, 3) == "\xEF\xBB\xBF") t.remove_prefix(3);
  const size_t first = t.find_first_not_of(" \t\r\n");
  return first == std::string_view::npos ? std::string_view() : t.substr(first);
}

bool isOpencvStorage(const std::string& text) {
  const std::string_view t = body(text);
  return t.substr(0, 6) == "%YAML:" ||
         (t.substr(0, 5) == "<?xml" && t.find("<opencv_storage>") != std::string_view::npos);
}

/// cv::FileStorage over the text; its parse errors become one-line ConfigErrors. OpenCV 4.6's parser
/// also lets standard exceptions out on some malformed files (std::length_error from a string it
/// sizes from the input: found by tests/fuzz, regressions/calibration): they are parse errors too.
cv::FileStorage openStorage(const std::string& text, const std::string& source) {
  std::string why;
  try {
    cv::FileStorage fs(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
    if (fs.isOpened()) return fs;
  } catch (const cv::Exception& e) {
    why = ": " + oneLine(e.err);
  } catch (const std::exception& e) {
    why = ": " + oneLine(e.what());
  }
  fail(source, "not a readable OpenCV FileStorage file" + why);
}

/// A numeric matrix node as CV_64F; fails naming the key unless it is rows x cols (or cols x rows
/// when `either_orientation`) of finite numbers.
cv::Mat readMatrix(const cv::FileStorage& fs, const std::string& key, int rows, int cols, bool either_orientation,
                   const std::string& source) {
  const cv::FileNode n = fs[key];
  if (n.empty() || n.isNone()) fail(source, "key '" + key + "' is missing");
  const auto shapeOk = [&](int r, int c) {
    return (r == rows && c == cols) || (either_orientation && r == cols && c == rows);
  };
  const auto wrongShape = [&](int r, int c, const std::string& more) {
    fail(source, "key '" + key + "' must be a " + std::to_string(rows) + "x" + std::to_string(cols) + " matrix" +
                     (either_orientation ? " (or its transpose)" : "") + ", found " + std::to_string(r) + "x" +
                     std::to_string(c) + more);
  };
  // OpenCV allocates the declared rows x cols before it reads the data: 3 KB declaring 2^31 columns
  // asked for 48 GB (found by tests/fuzz, regressions/calibration). The declared shape comes first.
  if (n.isMap() && !shapeOk(static_cast<int>(n["rows"]), static_cast<int>(n["cols"])))
    wrongShape(static_cast<int>(n["rows"]), static_cast<int>(n["cols"]), " (declared)");
  cv::Mat m;
  try {
    n >> m;
  } catch (const cv::Exception& e) {
    fail(source, "key '" + key + "' is not an OpenCV matrix: " + oneLine(e.err));
  }
  if (m.empty() || m.channels() != 1 || !shapeOk(m.rows, m.cols))
    wrongShape(m.rows, m.cols, m.channels() > 1 ? " with " + std::to_string(m.channels()) + " channels" : "");
  m.convertTo(m, CV_64F);
  for (int i = 0; i < m.rows; ++i)
    for (int j = 0; j < m.cols; ++j)
      if (!std::isfinite(m.at<double>(i, j))) fail(source, "key '" + key + "' holds a value that is not finite");
  return m;
}

/// Focal lengths, centre and skew of an OpenCV camera_matrix [fx s cx; 0 fy cy; 0 0 1].
void readCameraMatrix(const cv::FileStorage& fs, const std::string& source, double* fx, double* fy, double* cx,
                      double* cy, double* skew) {
  const cv::Mat K = readMatrix(fs, "camera_matrix", 3, 3, false, source);
  if (K.at<double>(1, 0) != 0.0 || K.at<double>(2, 0) != 0.0 || K.at<double>(2, 1) != 0.0 || K.at<double>(2, 2) != 1.0)
    fail(source, "key 'camera_matrix' must be [fx s cx; 0 fy cy; 0 0 1]");
  *fx = K.at<double>(0, 0);
  *fy = K.at<double>(1, 1);
  if (!(*fx > 0.0 && *fy > 0.0))
    fail(source, "key 'camera_matrix': fx and fy must be > 0, found " + fmt(*fx) + ", " + fmt(*fy));
  *skew = K.at<double>(0, 1);
  *cx = K.at<double>(0, 2);
  *cy = K.at<double>(1, 2);
}

/// image_width / image_height when the file has them (both or neither), else 0, 0.
void readOpencvSize(const cv::FileStorage& fs, const std::string& source, CameraCalibration* c) {
  const cv::FileNode w = fs["image_width"], h = fs["image_height"];
  if (w.isNone() && h.isNone()) return;
  for (const auto& [key, n] : {std::pair<const char*, cv::FileNode>{"image_width", w}, {"image_height", h}}) {
    if (!n.isInt() || static_cast<int>(n) < 1 || static_cast<int>(n) > 16384)
      fail(source, std::string("key '") + key +
                       "' must be an integer in [1, 16384] (with both image_width and "
                       "image_height given, or neither)");
  }
  c->width_px = static_cast<int>(w);
  c->height_px = static_cast<int>(h);
}

/// xi as a number or a 1x1 matrix; nullopt when the file has no xi.
std::optional<double> readXi(const cv::FileStorage& fs, const std::string& source) {
  const cv::FileNode n = fs["xi"];
  if (n.isNone()) return std::nullopt;
  const double xi =
      n.isReal() || n.isInt() ? static_cast<double>(n) : readMatrix(fs, "xi", 1, 1, false, source).at<double>(0, 0);
  if (!std::isfinite(xi) || xi < 0.0) fail(source, "key 'xi' must be a number >= 0, found " + fmt(xi));
  return xi;
}

/// parseOpencv's reading of an opened storage (OpenCV's own checks throw cv::Exception).
CameraCalibration readOpencv(const cv::FileStorage& fs, const std::string& source,
                             std::optional<CalibrationFormat> want) {
  CameraCalibration c;
  double fx = 0, fy = 0, cx = 0, cy = 0, skew = 0;
  readCameraMatrix(fs, source, &fx, &fy, &cx, &cy, &skew);
  readOpencvSize(fs, source, &c);
  const std::optional<double> xi = readXi(fs, source);
  const cv::FileNode dn = fs["distortion_coefficients"];
  // In 64 bits: the declared shape is not checked yet (readMatrix does that below), and a declared
  // rows x cols of 2^31 - 1 x 4 overflowed int (found by tests/fuzz, regressions/calibration).
  const int64_t n_dist =
      dn.isMap() ? static_cast<int64_t>(static_cast<int>(dn["rows"])) * static_cast<int>(dn["cols"]) : -1;
  if (want == CalibrationFormat::kOpencvFisheye && xi)
    fail(source, "key 'xi' found: an OpenCV omnidir (Mei) calibration, not a fisheye one");
  if (!xi && n_dist >= 5)
    fail(source, "key 'distortion_coefficients' has " + std::to_string(n_dist) +
                     " values and there is no 'xi': a pinhole calibration (cv::calibrateCamera), not an "
                     "omnidir (4 values and xi) or fisheye (4 values) one");
  if (want == CalibrationFormat::kOpencvOmnidir && !xi)
    fail(source, "key 'xi' is missing (an omnidir calibration has camera_matrix, distortion_coefficients, xi)");
  const cv::Mat D = readMatrix(fs, "distortion_coefficients", 1, 4, true, source);
  const double* d = D.ptr<double>();
  if (xi) {
    c.format = CalibrationFormat::kOpencvOmnidir;
    c.intrinsics = MeiIntrinsics{fx, fy, cx, cy, skew, *xi, d[0], d[1], d[2], d[3]};
    c.description = "OpenCV omnidir (Mei) calibration '" + source + "'";
  } else {
    c.format = CalibrationFormat::kOpencvFisheye;
    c.intrinsics = KannalaBrandtIntrinsics{fx, fy, cx, cy, skew, d[0], d[1], d[2], d[3]};
    c.description = "OpenCV fisheye (Kannala-Brandt) calibration '" + source + "'";
  }
  return c;
}

/// An OpenCV file as `want`, or (nullopt) as what it holds: omnidir with xi, fisheye without. OpenCV's
/// assertions become ConfigErrors too: a top level that is a list, not a map, made fs["camera_matrix"]
/// throw cv::Exception "isMap()" out of the reader (found by tests/fuzz, regressions/calibration).
CameraCalibration parseOpencv(const std::string& text, const std::string& source,
                              std::optional<CalibrationFormat> want) {
  const cv::FileStorage fs = openStorage(text, source);
  try {
    return readOpencv(fs, source, want);
  } catch (const cv::Exception& e) {
    fail(source, "not a readable OpenCV FileStorage file: " + oneLine(e.err));
  }
}

/// The Kalibr camera map: the one named, else the first key of the file whose value is a map.
config::Node kalibrCamera(const config::Node& root, const std::string& name, const std::string& source) {
  if (!name.empty()) {
    if (!root.has(name)) fail(source, "has no camera '" + name + "' (Kalibr cameras are cam0, cam1, ...)");
    return root.child(name);
  }
  for (const std::string& key : root.keys())
    if (root.optChild(key)) return root.child(key);
  fail(source, "holds no camera (a Kalibr camchain.yaml has cam0: {camera_model: ..., intrinsics: ...})");
}

/// "file: key 'cam0.x' (line N)" for messages of the Kalibr reader (config::Node::where() has no
/// line; its getters add one themselves).
std::string whereLine(const config::Node& cam, const std::string& key, const std::string& text) {
  std::string line;
  try {
    const YAML::Node n = YAML::Load(text)[cam.path()][key];
    if (n && n.Mark().line >= 0) line = " (line " + std::to_string(n.Mark().line + 1) + ")";
  } catch (const YAML::Exception&) {
    // already parsed once by config::Node: cannot happen; the key is still named
  }
  return cam.where(key) + line;
}

/// intrinsics, checked: `n` finite numbers whose focal lengths (at `f`, `f + 1`) are > 0.
std::vector<double> kalibrIntrinsics(const config::Node& cam, size_t n, size_t f, const std::string& text) {
  std::vector<double> v = cam.getDoubles("intrinsics", n, -1e12, 1e12);
  if (!(v[f] > 0.0 && v[f + 1] > 0.0))
    throw ConfigError(whereLine(cam, "intrinsics", text) + " focal lengths fu, fv must be > 0, found " + fmt(v[f]) +
                      ", " + fmt(v[f + 1]));
  return v;
}

CalibratedIntrinsics kalibrModel(const config::Node& cam, const std::string& model, const std::string& dist,
                                 const std::string& text) {
  const size_t n_dist = dist == "none" ? 0 : 4;
  const std::vector<double> d = cam.has("distortion_coeffs") || n_dist > 0
                                    ? cam.getDoubles("distortion_coeffs", n_dist, -1e12, 1e12)
                                    : std::vector<double>{};
  if (model == "omni") {
    const auto v = kalibrIntrinsics(cam, 5, 1, text);
    if (v[0] < 0.0)
      throw ConfigError(whereLine(cam, "intrinsics", text) + " xi (item 0) must be >= 0, found " + fmt(v[0]));
    MeiIntrinsics m{v[1], v[2], v[3], v[4], 0.0, v[0]};
    if (n_dist) {
      m.k1 = d[0];
      m.k2 = d[1];
      m.p1 = d[2];
      m.p2 = d[3];
    }
    return m;
  }
  if (model == "pinhole") {
    const auto v = kalibrIntrinsics(cam, 4, 0, text);
    return KannalaBrandtIntrinsics{v[0], v[1], v[2], v[3], 0.0, d[0], d[1], d[2], d[3]};
  }
  if (model == "ds") {
    const auto v = kalibrIntrinsics(cam, 6, 2, text);
    if (!(v[1] >= 0.0 && v[1] <= 1.0))
      throw ConfigError(whereLine(cam, "intrinsics", text) + " alpha (item 1) must be in [0, 1], found " + fmt(v[1]));
    return DoubleSphereIntrinsics{v[2], v[3], v[4], v[5], v[0], v[1]};
  }
  const auto v = kalibrIntrinsics(cam, 6, 2, text);  // eucm
  if (!(v[0] >= 0.0 && v[0] <= 1.0) || !(v[1] > 0.0))
    throw ConfigError(whereLine(cam, "intrinsics", text) +
                      " alpha (item 0) must be in [0, 1] and beta (item 1) > 0, found " + fmt(v[0]) + ", " + fmt(v[1]));
  return EucmIntrinsics{v[2], v[3], v[4], v[5], v[0], v[1]};
}

CameraCalibration parseKalibr(const std::string& text, const std::string& source, const std::string& camera) {
  const config::Node root = config::Node::loadString(text, source);
  const config::Node cam = kalibrCamera(root, camera, source);
  const std::string model = cam.getString("camera_model");
  const std::string dist = cam.getString("distortion_model");
  const bool ok = (model == "omni" && (dist == "radtan" || dist == "none")) ||
                  (model == "pinhole" && dist == "equidistant") ||
                  ((model == "ds" || model == "eucm") && dist == "none");
  if (!ok)
    throw ConfigError(whereLine(cam, "camera_model", text) + " " + model + " + " + dist +
                      " is not supported; supported (camera_model + distortion_model): omni + radtan, omni + none, "
                      "pinhole + equidistant, ds + none, eucm + none");
  CameraCalibration c;
  c.format = CalibrationFormat::kKalibr;
  c.intrinsics = kalibrModel(cam, model, dist, text);
  if (cam.has("resolution")) {
    const std::vector<double> r = cam.getDoubles("resolution", 2, 1.0, 16384.0);
    if (r[0] != std::floor(r[0]) || r[1] != std::floor(r[1]))
      throw ConfigError(whereLine(cam, "resolution", text) + " must be two whole numbers [width, height]");
    c.width_px = static_cast<int>(r[0]);
    c.height_px = static_cast<int>(r[1]);
  }
  c.description = "Kalibr " + cam.path() + " (" + model + " + " + dist + ") of '" + source + "'";
  return c;
}

CameraCalibration parseOcam(const std::string& text, const std::string& source) {
  const camera::OcamCalibParseResult r = camera::parseOcamCalib(text);
  if (!r.params) fail(source, r.error);
  CameraCalibration c;
  c.format = CalibrationFormat::kOcamcalib;
  c.intrinsics = *r.params;
  c.width_px = r.params->width_px;
  c.height_px = r.params->height_px;
  c.description = "OCamCalib calibration '" + source + "'";
  return c;
}

CameraCalibration parseAs(CalibrationFormat f, const std::string& text, const std::string& source,
                          const CalibrationReadOptions& o) {
  switch (f) {
    case CalibrationFormat::kOpencvOmnidir:
    case CalibrationFormat::kOpencvFisheye:
      if (!isOpencvStorage(text))
        fail(source, "not an OpenCV FileStorage file (its first line must be %YAML:1.0, or an XML <opencv_storage>)");
      return parseOpencv(text, source, f);
    case CalibrationFormat::kKalibr: return parseKalibr(text, source, o.kalibr_camera);
    case CalibrationFormat::kOcamcalib: break;
  }
  return parseOcam(text, source);
}

/// A YAML map that looks like an OpenCV calibration written without FileStorage's header.
bool isHeaderlessOpencvYaml(const std::string& text) {
  try {
    const YAML::Node n = YAML::Load(text);
    return n.IsMap() && n["camera_matrix"];
  } catch (const YAML::Exception&) {
    return false;
  }
}

/// Model M built from P after validate(); ConfigError naming the calibration on refusal.
template <class M, class P>
std::unique_ptr<camera::CameraModel> validated(const P& p, const CameraCalibration& c) {
  if (auto why = M::validate(p)) throw ConfigError(c.description + ": " + *why);
  return std::make_unique<M>(p);
}

/// Focal lengths, centre and image size of any params struct (fields named as in the core).
template <class P, class I>
P withCommon(const I& i, int w, int h) {
  P p;
  p.fx_px = i.fx_px;
  p.fy_px = i.fy_px;
  p.cx_px = i.cx_px;
  p.cy_px = i.cy_px;
  p.width_px = w;
  p.height_px = h;
  return p;
}

struct ModelMaker {
  const CameraCalibration& c;
  camera::OcamOptics optics;
  int w, h;
  std::unique_ptr<camera::CameraModel> operator()(const MeiIntrinsics& i) const {
    auto p = withCommon<camera::MeiParams>(i, w, h);
    p.skew_px = i.skew_px;
    p.xi = i.xi;
    p.k1 = i.k1;
    p.k2 = i.k2;
    p.p1 = i.p1;
    p.p2 = i.p2;
    return validated<camera::MeiCamera>(p, c);
  }
  std::unique_ptr<camera::CameraModel> operator()(const KannalaBrandtIntrinsics& i) const {
    auto p = withCommon<camera::KannalaBrandtParams>(i, w, h);
    p.skew_px = i.skew_px;
    p.k1 = i.k1;
    p.k2 = i.k2;
    p.k3 = i.k3;
    p.k4 = i.k4;
    return validated<camera::KannalaBrandtCamera>(p, c);
  }
  std::unique_ptr<camera::CameraModel> operator()(const DoubleSphereIntrinsics& i) const {
    auto p = withCommon<camera::DoubleSphereParams>(i, w, h);
    p.xi = i.xi;
    p.alpha = i.alpha;
    return validated<camera::DoubleSphereCamera>(p, c);
  }
  std::unique_ptr<camera::CameraModel> operator()(const EucmIntrinsics& i) const {
    auto p = withCommon<camera::EucmParams>(i, w, h);
    p.alpha = i.alpha;
    p.beta = i.beta;
    return validated<camera::EucmCamera>(p, c);
  }
  std::unique_ptr<camera::CameraModel> operator()(const camera::ScaramuzzaParams& i) const {
    camera::ScaramuzzaParams p = i;
    p.optics = optics;
    p.width_px = w;
    p.height_px = h;
    return validated<camera::ScaramuzzaCamera>(p, c);
  }
};

}  // namespace

std::unique_ptr<camera::CameraModel> makeCalibratedCamera(const CameraCalibration& calibration,
                                                          camera::OcamOptics optics, int width_px, int height_px) {
  auto model = std::visit(ModelMaker{calibration, optics, width_px, height_px}, calibration.intrinsics);
  const bool reflect = optics == camera::OcamOptics::kCatadioptric &&
                       !std::holds_alternative<camera::ScaramuzzaParams>(calibration.intrinsics);
  return reflect ? std::make_unique<camera::ReflectedCamera>(std::move(model)) : std::move(model);
}

Eigen::Vector2d principalPointPx(const CameraCalibration& calibration) {
  return std::visit(
      [](const auto& i) -> Eigen::Vector2d {
        if constexpr (std::is_same_v<std::decay_t<decltype(i)>, camera::ScaramuzzaParams>)
          return {i.yc_col_px, i.xc_row_px};
        else return {i.cx_px, i.cy_px};
      },
      calibration.intrinsics);
}

std::string formatKey(CalibrationFormat f) {
  switch (f) {
    case CalibrationFormat::kOpencvOmnidir: return "opencv_omnidir";
    case CalibrationFormat::kOpencvFisheye: return "opencv_fisheye";
    case CalibrationFormat::kKalibr: return "kalibr";
    case CalibrationFormat::kOcamcalib: break;
  }
  return "ocamcalib";
}

std::string formatDescription(CalibrationFormat f) {
  switch (f) {
    case CalibrationFormat::kOpencvOmnidir: return "an OpenCV omnidir (Mei) FileStorage file";
    case CalibrationFormat::kOpencvFisheye: return "an OpenCV fisheye FileStorage file";
    case CalibrationFormat::kKalibr: return "a Kalibr camchain.yaml";
    case CalibrationFormat::kOcamcalib: break;
  }
  return "an OCamCalib calib_results.txt";
}

std::optional<CalibrationFormat> detectCalibrationFormat(const std::string& text) {
  if (isOpencvStorage(text)) {
    try {
      const cv::FileStorage fs(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
      if (!fs.isOpened() || fs["camera_matrix"].isNone()) return std::nullopt;
      return fs["xi"].isNone() ? CalibrationFormat::kOpencvFisheye : CalibrationFormat::kOpencvOmnidir;
    } catch (const std::exception&) {  // cv::Exception, and what OpenCV's parser lets out (openStorage)
      return std::nullopt;
    }
  }
  try {
    const YAML::Node root = YAML::Load(text);
    if (root.IsMap())
      for (const auto& kv : root)
        if (kv.second.IsMap() && kv.second["camera_model"]) return CalibrationFormat::kKalibr;
  } catch (const YAML::Exception&) {
    // not YAML: may still be OCamCalib's text
  }
  if (text.find("ocam_model.ss") != std::string::npos || camera::parseOcamCalib(text).params)
    return CalibrationFormat::kOcamcalib;
  return std::nullopt;
}

CameraCalibration parseCalibration(const std::string& text, const std::string& source,
                                   const CalibrationReadOptions& options) {
  if (!options.format) {
    const std::optional<CalibrationFormat> f = detectCalibrationFormat(text);
    if (f) return parseAs(*f, text, source, options);
    if (isOpencvStorage(text)) return parseOpencv(text, source, std::nullopt);  // says what is wrong
    if (isHeaderlessOpencvYaml(text))
      fail(source, "looks like an OpenCV calibration but lacks FileStorage's first line '%YAML:1.0'");
    fail(source, std::string("unknown calibration format; ") + kAccepted);
  }
  try {
    return parseAs(*options.format, text, source, options);
  } catch (const ConfigError&) {
    const std::optional<CalibrationFormat> found = detectCalibrationFormat(text);
    if (found && *found != *options.format)
      fail(source, "is " + formatDescription(*found) + ", not " + formatDescription(*options.format) +
                       ": read it as '" + formatKey(*found) + "' or 'auto'");
    throw;
  }
}

CameraCalibration readCalibrationFile(const std::string& path, const CalibrationReadOptions& options) {
  std::ifstream f(path, std::ios::binary);
  if (!f) fail(path, "cannot be read");
  std::stringstream ss;
  ss << f.rdbuf();
  if (f.bad()) fail(path, "cannot be read");
  return parseCalibration(ss.str(), path, options);
}

}  // namespace omnislam::vision
