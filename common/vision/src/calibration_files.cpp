// Readers of OpenCV / Kalibr / OCamCalib calibration files: see calibration_files.h.
#include "omnislam/vision/calibration_files.h"

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
#include "opencv_storage.h"

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

using detail::OpencvMatrix;
using detail::OpencvNumber;
using detail::OpencvOther;
using detail::OpencvValue;
using detail::OpencvValues;

/// The value at `key` ("missing" when absent).
const OpencvValue& valueAt(const OpencvValues& v, const std::string& key) {
  static const OpencvValue missing = detail::OpencvMissing{};
  const auto it = v.find(key);
  return it == v.end() ? missing : it->second;
}

bool present(const OpencvValues& v, const std::string& key) {
  return !std::holds_alternative<detail::OpencvMissing>(valueAt(v, key));
}

/// A numeric matrix's values (row-major); fails naming the key unless it is rows x cols (or cols x
/// rows when `either_orientation`) of finite numbers. The declared shape is checked before the values
/// (which are not read for large shapes: opencv_storage.h).
std::vector<double> readMatrix(const OpencvValues& v, const std::string& key, int rows, int cols,
                               bool either_orientation, const std::string& source) {
  const OpencvValue& n = valueAt(v, key);
  if (!present(v, key)) fail(source, "key '" + key + "' is missing");
  if (const auto* o = std::get_if<OpencvOther>(&n)) fail(source, "key '" + key + "' is " + o->what);
  const auto* m = std::get_if<OpencvMatrix>(&n);
  if (!m) fail(source, "key '" + key + "' is a number, not an OpenCV matrix (!!opencv-matrix)");
  const bool shape_ok =
      (m->rows == rows && m->cols == cols) || (either_orientation && m->rows == cols && m->cols == rows);
  if (!shape_ok || m->channels != 1 || m->values.empty())
    fail(source, "key '" + key + "' must be a " + std::to_string(rows) + "x" + std::to_string(cols) + " matrix" +
                     (either_orientation ? " (or its transpose)" : "") + ", found " + std::to_string(m->rows) + "x" +
                     std::to_string(m->cols) +
                     (m->channels > 1 ? " with " + std::to_string(m->channels) + " channels" : "") +
                     (m->values.empty() ? " (declared)" : ""));
  for (const double x : m->values)
    if (!std::isfinite(x)) fail(source, "key '" + key + "' holds a value that is not finite");
  return m->values;
}

/// Focal lengths, centre and skew of an OpenCV camera_matrix [fx s cx; 0 fy cy; 0 0 1].
void readCameraMatrix(const OpencvValues& v, const std::string& source, double* fx, double* fy, double* cx, double* cy,
                      double* skew) {
  const std::vector<double> K = readMatrix(v, "camera_matrix", 3, 3, false, source);
  if (K[3] != 0.0 || K[6] != 0.0 || K[7] != 0.0 || K[8] != 1.0)
    fail(source, "key 'camera_matrix' must be [fx s cx; 0 fy cy; 0 0 1]");
  *fx = K[0];
  *fy = K[4];
  if (!(*fx > 0.0 && *fy > 0.0))
    fail(source, "key 'camera_matrix': fx and fy must be > 0, found " + fmt(*fx) + ", " + fmt(*fy));
  *skew = K[1];
  *cx = K[2];
  *cy = K[5];
}

/// image_width / image_height when the file has them (both or neither), else 0, 0.
void readOpencvSize(const OpencvValues& v, const std::string& source, CameraCalibration* c) {
  if (!present(v, "image_width") && !present(v, "image_height")) return;
  int size[2] = {0, 0};
  for (const int i : {0, 1}) {
    const char* key = i == 0 ? "image_width" : "image_height";
    const auto* n = std::get_if<OpencvNumber>(&valueAt(v, key));
    if (!n || !n->whole || n->value < 1 || n->value > 16384)
      fail(source, std::string("key '") + key +
                       "' must be an integer in [1, 16384] (with both image_width and "
                       "image_height given, or neither)");
    size[i] = static_cast<int>(n->value);
  }
  c->width_px = size[0];
  c->height_px = size[1];
}

/// xi as a number or a 1x1 matrix; nullopt when the file has no xi.
std::optional<double> readXi(const OpencvValues& v, const std::string& source) {
  if (!present(v, "xi")) return std::nullopt;
  const auto* n = std::get_if<OpencvNumber>(&valueAt(v, "xi"));
  const double xi = n ? n->value : readMatrix(v, "xi", 1, 1, false, source)[0];
  if (!std::isfinite(xi) || xi < 0.0) fail(source, "key 'xi' must be a number >= 0, found " + fmt(xi));
  return xi;
}

/// The number of distortion values declared (rows x cols, in 64 bits: a declared 2^31 - 1 x 4
/// overflowed int, found by tests/fuzz), or -1 when it is not a matrix.
int64_t declaredDistortionCount(const OpencvValues& v) {
  const auto* m = std::get_if<OpencvMatrix>(&valueAt(v, "distortion_coefficients"));
  return m ? m->rows * m->cols : -1;
}

/// An OpenCV file's values as `want`, or (nullopt) as what it holds: omnidir with xi, fisheye without.
CameraCalibration readOpencv(const OpencvValues& v, const std::string& source, std::optional<CalibrationFormat> want) {
  CameraCalibration c;
  double fx = 0, fy = 0, cx = 0, cy = 0, skew = 0;
  readCameraMatrix(v, source, &fx, &fy, &cx, &cy, &skew);
  readOpencvSize(v, source, &c);
  const std::optional<double> xi = readXi(v, source);
  const int64_t n_dist = declaredDistortionCount(v);
  if (want == CalibrationFormat::kOpencvFisheye && xi)
    fail(source, "key 'xi' found: an OpenCV omnidir (Mei) calibration, not a fisheye one");
  if (!xi && n_dist >= 5)
    fail(source, "key 'distortion_coefficients' has " + std::to_string(n_dist) +
                     " values and there is no 'xi': a pinhole calibration (cv::calibrateCamera), not an "
                     "omnidir (4 values and xi) or fisheye (4 values) one");
  if (want == CalibrationFormat::kOpencvOmnidir && !xi)
    fail(source, "key 'xi' is missing (an omnidir calibration has camera_matrix, distortion_coefficients, xi)");
  const std::vector<double> d = readMatrix(v, "distortion_coefficients", 1, 4, true, source);
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

CameraCalibration parseOpencv(const std::string& text, const std::string& source,
                              std::optional<CalibrationFormat> want) {
  return readOpencv(detail::readOpencvValues(text, source, detail::opencvCalibrationKeys()), source, want);
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
      const OpencvValues v = detail::readOpencvValues(text, "", {"camera_matrix", "xi"});
      if (!present(v, "camera_matrix")) return std::nullopt;
      return present(v, "xi") ? CalibrationFormat::kOpencvOmnidir : CalibrationFormat::kOpencvFisheye;
    } catch (const ConfigError&) {
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
