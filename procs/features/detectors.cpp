// Detectors of omnislam-features: see detectors.h.
#include "detectors.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "detector_options_table.h"
#include "omnislam/config/options_parse.h"
#include "omnislam/config/world_config.h"
#include "omnislam/core/angles.h"
#include "omnislam/core/camera/pajdla_bakstein.h"
#include "omnislam/core/camera/scaramuzza.h"
#include "omnislam/vision/annotate.h"
#include "omnislam/vision/calibration_files.h"
#include "omnislam/vision/ceiling_lights.h"
#include "omnislam/vision/image_mask.h"
#include "omnislam/vision/vertical_lines.h"

namespace omnislam::features {
namespace {

using config::ConfigError;
using config::Node;

struct CameraSetup {
  std::unique_ptr<camera::CameraModel> model;  ///< null for centre_only
  camera::CameraMounting mounting;
  int width_px = 0, height_px = 0;
  std::optional<Eigen::Vector2d> centre_px;  ///< the model's image centre, when it has one
  std::string description;
  cv::Mat mask;  ///< CV_8UC1 of the camera's size, 255 = pixels the detectors use; empty = all (parseMask)
};

/// The largest tilt of the optical axis from the robot's vertical (roll and pitch of the mounting)
/// that the vertical-line detector accepts [deg]: it looks for vertical lines as radial lines about
/// the image centre. A tilt tau slants a line spanning elevations e1..e2 by about
/// tau (tan e2 - tan e1) of image angle: 0.5 deg x 2.23 (-5..65 deg, the room's band) = 1.1 deg,
/// inside the default max_drift_columns (6 of 1440 columns = 1.5 deg). docs/design/detectors.md.
constexpr double kMaxLinesTiltDeg = 0.5;

camera::CameraMounting parseMounting(const Node& m) {
  m.rejectUnknownKeys({"x_m", "y_m", "z_m", "yaw_deg", "pitch_deg", "roll_deg"});
  camera::CameraMounting out;
  out.x_m = m.getDouble("x_m", -10.0, 10.0, 0.0);
  out.y_m = m.getDouble("y_m", -10.0, 10.0, 0.0);
  out.z_m = m.getDouble("z_m", -10.0, 10.0);
  out.yaw_rad = deg2rad(m.getDouble("yaw_deg", -180.0, 180.0, 0.0));
  out.pitch_rad = deg2rad(m.getDouble("pitch_deg", -90.0, 90.0, 0.0));
  out.roll_rad = deg2rad(m.getDouble("roll_deg", -180.0, 180.0, 0.0));
  return out;
}

/// Keys that only some camera models read are refused for the others, not ignored.
void refuseKeys(const Node& c, std::initializer_list<const char*> keys, const std::string& model, const char* why) {
  for (const char* k : keys)
    if (c.has(k)) throw ConfigError(c.where(k) + " is not read for model '" + model + "' (" + why + ")");
}

/// The OCamCalib camera of a calibration, with the config's optics and valid region (as before the
/// other formats existed, so that these configs give the same output).
void ocamSetup(const Node& c, camera::ScaramuzzaParams p, const std::string& path, CameraSetup* s) {
  p.optics = c.getEnum("optics", {"catadioptric", "dioptric"}, "catadioptric") == "catadioptric"
                 ? camera::OcamOptics::kCatadioptric
                 : camera::OcamOptics::kDioptric;
  p.min_elevation_rad = deg2rad(c.getDouble("min_elevation_deg", -90.0, 90.0, -90.0));
  p.max_elevation_rad = deg2rad(c.getDouble("max_elevation_deg", -90.0, 90.0, 90.0));
  p.min_radius_px = c.getDouble("min_radius_px", 0.0, 1e5, 0.0);
  if (c.has("max_radius_px")) p.max_radius_px = c.getDouble("max_radius_px", 1.0, 1e5);
  if (auto why = camera::ScaramuzzaCamera::validate(p)) throw ConfigError(c.where("file") + " " + *why);
  s->model = std::make_unique<camera::ScaramuzzaCamera>(p);
  s->centre_px = Eigen::Vector2d(p.yc_col_px, p.xc_row_px);
  s->description = "OCamCalib camera from " + path;
}

/// Image size of a calibration: the file's, else camera.width_px / height_px; both must agree.
std::pair<int, int> calibrationSize(const Node& c, const vision::CameraCalibration& cal, const std::string& path) {
  if (cal.width_px == 0) {
    if (!c.has("width_px") || !c.has("height_px"))
      throw ConfigError(c.where("file") + " '" + path +
                        "' states no image size: set camera.width_px and camera.height_px");
    return {static_cast<int>(c.getInt("width_px", 1, 16384)), static_cast<int>(c.getInt("height_px", 1, 16384))};
  }
  for (const auto& [key, v] : {std::pair<const char*, int>{"width_px", cal.width_px}, {"height_px", cal.height_px}})
    if (c.has(key) && c.getInt(key, 1, 16384) != v)
      throw ConfigError(c.where(key) + " is " + std::to_string(c.getInt(key, 1, 16384)) + " but '" + path + "' says " +
                        std::to_string(v));
  return {cal.width_px, cal.height_px};
}

/// A camera from a calibration file: model auto (detect by content) or one named format.
void fileSetup(const Node& c, const std::string& model, CameraSetup* s) {
  const std::string path = c.getExistingFile("file");
  vision::CalibrationReadOptions opt;
  const std::vector<std::pair<std::string, vision::CalibrationFormat>> formats = {
      {"opencv_omnidir", vision::CalibrationFormat::kOpencvOmnidir},
      {"opencv_fisheye", vision::CalibrationFormat::kOpencvFisheye},
      {"kalibr", vision::CalibrationFormat::kKalibr},
      {"ocamcalib", vision::CalibrationFormat::kOcamcalib}};
  for (const auto& [key, f] : formats)
    if (model == key) opt.format = f;
  opt.kalibr_camera = c.getString("kalibr_camera", "");
  vision::CameraCalibration cal;
  try {
    cal = vision::readCalibrationFile(path, opt);
  } catch (const ConfigError& e) {
    throw ConfigError(c.where("file") + " " + e.what());
  }
  if (cal.format != vision::CalibrationFormat::kKalibr && c.has("kalibr_camera"))
    throw ConfigError(c.where("kalibr_camera") + " is for Kalibr files; '" + path + "' is " +
                      vision::formatDescription(cal.format));
  if (cal.format == vision::CalibrationFormat::kOcamcalib) {
    ocamSetup(c, std::get<camera::ScaramuzzaParams>(cal.intrinsics), path, s);
    calibrationSize(c, cal, path);  // width_px / height_px, when given, must agree
    return;
  }
  refuseKeys(c, {"min_elevation_deg", "max_elevation_deg", "min_radius_px", "max_radius_px"}, model,
             "the valid region of OCamCalib models only");
  if (!c.has("optics"))
    throw ConfigError(c.where("optics") + " is required for " + vision::formatDescription(cal.format) +
                      ": catadioptric (camera looking into a mirror) or dioptric (lens)");
  const auto optics = c.getEnum("optics", {"catadioptric", "dioptric"}) == "catadioptric"
                          ? camera::OcamOptics::kCatadioptric
                          : camera::OcamOptics::kDioptric;
  const auto [w, h] = calibrationSize(c, cal, path);
  try {
    s->model = vision::makeCalibratedCamera(cal, optics, w, h);
  } catch (const ConfigError& e) {
    throw ConfigError(c.where("file") + " " + e.what());
  }
  s->centre_px = vision::principalPointPx(cal);
  s->description = cal.description + (optics == camera::OcamOptics::kCatadioptric ? ", catadioptric" : ", dioptric");
}

// camera.mask (an image file, non-zero = use) and camera.mask_annulus (a ring about the mirror's
// centre), combined by AND (image_mask.h); loaded once at start. Empty when neither is given.
cv::Mat parseMask(const Node& c, int width_px, int height_px) {
  cv::Mat mask;
  if (c.has("mask")) {
    vision::MaskFile f = vision::readMask(c.getExistingFile("mask"), width_px, height_px);
    if (!f.error.empty()) throw ConfigError(c.where("mask") + " " + f.error);
    mask = f.mask;
  }
  if (c.has("mask_annulus")) {
    const Node a = c.child("mask_annulus");
    a.rejectUnknownKeys({"centre_u_px", "centre_v_px", "r_min_px", "r_max_px"});
    vision::MaskAnnulus an;
    an.centre_u_px = a.getDouble("centre_u_px", -0.5, width_px - 0.5);
    an.centre_v_px = a.getDouble("centre_v_px", -0.5, height_px - 0.5);
    an.r_min_px = a.getDouble("r_min_px", 0.0, 1e5);
    an.r_max_px = a.getDouble("r_max_px", 1.0, 1e5);
    if (!(an.r_max_px > an.r_min_px)) throw ConfigError(a.where("r_max_px") + " must be > r_min_px");
    mask = vision::combineMasks(mask, vision::annulusMask(an, width_px, height_px));
  }
  if (!mask.empty() && cv::countNonZero(mask) == 0)
    throw ConfigError(c.where(c.has("mask_annulus") ? "mask_annulus" : "mask") + " leaves no pixel to use");
  return mask;
}

CameraSetup parseCamera(const Node& c) {
  c.rejectUnknownKeys({"model", "world", "file", "kalibr_camera", "optics", "min_elevation_deg", "max_elevation_deg",
                       "min_radius_px", "max_radius_px", "width_px", "height_px", "mounting", "mask", "mask_annulus"});
  CameraSetup s;
  const std::string model =
      c.getEnum("model", {"world", "auto", "opencv_omnidir", "opencv_fisheye", "kalibr", "ocamcalib", "centre_only"});
  if (model == "world") {
    const sim::World w = config::loadWorld(c.getExistingFile("world"));
    s.model = sim::makeCamera(w.camera);  // the world's model: Pajdla-Bakstein or Scaramuzza
    s.mounting = c.has("mounting") ? parseMounting(c.child("mounting")) : w.camera.mounting;
    s.centre_px = sim::cameraCentrePx(w.camera);
    s.description = s.model->name() + " camera of world '" + w.name + "'";
  } else if (model == "centre_only") {
    s.mounting = parseMounting(c.child("mounting"));
    s.description = "centre-only geometry (azimuth = image angle about the panorama centre)";
  } else {
    fileSetup(c, model, &s);
    s.mounting = parseMounting(c.child("mounting"));
  }
  if (s.model) {
    s.width_px = s.model->widthPx();
    s.height_px = s.model->heightPx();
  } else {
    s.width_px = static_cast<int>(c.getInt("width_px", 1, 16384));
    s.height_px = static_cast<int>(c.getInt("height_px", 1, 16384));
  }
  s.mask = parseMask(c, s.width_px, s.height_px);
  return s;
}

/// The vertical-line detector needs the optical axis along the robot's vertical (see
/// kMaxLinesTiltDeg): a tilted mounting is refused, naming its keys.
void checkLevelForLines(const Node& c, const CameraSetup& s) {
  const double tilt_deg = rad2deg(std::acos(std::clamp(camera::rotationCameraToRobot(s.mounting)(2, 2), -1.0, 1.0)));
  if (tilt_deg > kMaxLinesTiltDeg) {
    std::ostringstream m;
    m << (c.has("mounting") ? c.child("mounting").where("pitch_deg") : c.where("world")) << " and 'roll_deg' tilt the "
      << "optical axis " << tilt_deg << " deg from the robot's vertical; vertical_lines needs at most "
      << kMaxLinesTiltDeg << " deg (it finds vertical lines as radial lines about the image centre)";
    throw ConfigError(m.str());
  }
}

// Reads only the image's header fields (omnislam-features also runs it on vision::HeaderProbe, the
// dimensions of an encoded image before decoding). The size is judged first: a frame of another
// camera is named as such whatever its format; the message gives what came and what is needed.
std::string checkSizeAndFormat(const cv::Mat& img, int w, int h, bool colour_ok) {
  if (img.empty()) return "empty image";
  const bool size_ok = img.cols == w && img.rows == h;
  if (size_ok && img.depth() == CV_8U && (img.channels() == 1 || (colour_ok && img.channels() == 3))) return {};
  static const char* const kDepth[] = {"8-bit",          "8-bit signed", "16-bit",       "16-bit signed",
                                       "32-bit integer", "32-bit float", "64-bit float", "16-bit float"};
  auto dims = [](int cols, int rows) { return std::to_string(cols) + "x" + std::to_string(rows); };
  return (size_ok ? std::string("format") : "size " + dims(img.cols, img.rows)) +
         " does not match the camera (received " + dims(img.cols, img.rows) + ", " + std::to_string(img.channels()) +
         (img.channels() == 1 ? " channel, " : " channels, ") + kDepth[img.depth()] + "; the camera needs " +
         dims(w, h) + ", 8-bit " + (colour_ok ? "grey or BGR)" : "grey)");
}

class LightsDetector final : public Detector {
 public:
  LightsDetector(CameraSetup cam, const vision::CeilingLightOptions& opt, int max_features)
      : cam_(std::move(cam)),
        det_(*cam_.model, cam_.mounting, opt),
        max_features_(max_features),
        options_(describeOptions(opt)) {}
  std::string name() const override { return "ceiling_lights"; }
  std::string options() const override { return options_; }
  std::optional<std::string> check(const cv::Mat& img) const override {
    auto why = checkSizeAndFormat(img, cam_.width_px, cam_.height_px, false);
    return why.empty() ? std::nullopt : std::optional<std::string>(why);
  }
  std::vector<feature_t> detect(const cv::Mat& img) const override {
    auto lights = det_.detect(img, cam_.mask);  // camera.mask: blobs touching it are cut (truncated)
    if (static_cast<int>(lights.size()) > max_features_) lights.resize(static_cast<size_t>(max_features_));
    last_ = lights;
    std::vector<feature_t> out;
    for (const auto& L : lights) {
      feature_t f{};
      f.kind = feature_t::KIND_CEILING_LIGHT;
      f.azimuth_rad = L.azimuth_rad;
      f.elevation_rad = L.elevation_rad;
      f.has_elevation = true;
      for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) f.covariance[i][j] = L.covariance(i, j);
      f.u_px = L.blob.u_px;
      f.v_px = L.blob.v_px;
      f.size_px = L.blob.area_px;
      f.length_px = L.blob.major_axis_px;
      f.strength = L.blob.peak_grey;
      // Mean grey of the blob (the IR image is grey): mass / area + its local background.
      const float mean = static_cast<float>(L.blob.mass / std::max(1, L.blob.area_px) + L.blob.background_grey);
      for (int i = 0; i < 3; ++i) f.colour_a[i] = mean;
      out.push_back(f);
    }
    return out;
  }
  cv::Mat annotate(const cv::Mat& img, const std::vector<feature_t>&) const override {
    return vision::annotateLights(img, last_);
  }
  camera::CameraMounting mounting() const override { return cam_.mounting; }
  std::string describe() const override { return "ceiling lights, " + cam_.description; }

 private:
  CameraSetup cam_;
  vision::CeilingLightDetector det_;
  int max_features_;
  std::string options_;
  mutable std::vector<vision::CeilingLight> last_;
};

class LinesDetector final : public Detector {
 public:
  LinesDetector(CameraSetup cam, const vision::VerticalLineOptions& opt, int max_features)
      : cam_(std::move(cam)),
        det_(opt, cam_.width_px, cam_.height_px, cam_.model.get(), cam_.mounting, cam_.mask),
        max_features_(max_features),
        options_(describeOptions(opt)) {}
  std::string name() const override { return "vertical_lines"; }
  std::string options() const override { return options_; }
  std::optional<std::string> check(const cv::Mat& img) const override {
    auto why = checkSizeAndFormat(img, cam_.width_px, cam_.height_px, true);
    return why.empty() ? std::nullopt : std::optional<std::string>(why);
  }
  std::vector<feature_t> detect(const cv::Mat& img) const override {
    auto lines = det_.detect(img);
    if (static_cast<int>(lines.size()) > max_features_) {
      std::sort(lines.begin(), lines.end(),
                [](const auto& a, const auto& b) { return a.strength * a.length_px > b.strength * b.length_px; });
      lines.resize(static_cast<size_t>(max_features_));
      std::sort(lines.begin(), lines.end(), [](const auto& a, const auto& b) { return a.azimuth_rad < b.azimuth_rad; });
    }
    last_ = lines;
    std::vector<feature_t> out;
    for (const auto& L : lines) {
      feature_t f{};
      f.kind = feature_t::KIND_VERTICAL_LINE;
      f.azimuth_rad = L.azimuth_rad;
      f.elevation_rad = 0.0;
      f.has_elevation = false;
      f.covariance[0][0] = L.variance_rad2;
      f.u_px = L.px_inner.x();
      f.v_px = L.px_inner.y();
      f.size_px = 1.0;
      f.length_px = L.length_px;
      f.strength = L.strength;
      for (int i = 0; i < 3; ++i) {
        f.colour_a[i] = L.colour_ccw[static_cast<size_t>(i)];
        f.colour_b[i] = L.colour_cw[static_cast<size_t>(i)];
      }
      out.push_back(f);
    }
    return out;
  }
  cv::Mat annotate(const cv::Mat& img, const std::vector<feature_t>&) const override {
    return vision::annotateLines(img, last_, det_.panorama().options());
  }
  camera::CameraMounting mounting() const override { return cam_.mounting; }
  std::string describe() const override {
    const auto& p = det_.panorama().options();
    std::ostringstream s;
    s << "vertical lines, " << cam_.description << ", panorama centre (" << p.centre_u_px << ", " << p.centre_v_px
      << ") px, radii " << p.r_min_px << ".." << p.r_max_px << " px, " << p.columns << " columns";
    if (!cam_.mask.empty())
      s << ", mask uses " << std::lround(100.0 * vision::usedFraction(cam_.mask)) << " % of the pixels";
    return s.str();
  }

 private:
  CameraSetup cam_;
  vision::VerticalLineDetector det_;
  int max_features_;
  std::string options_;
  mutable std::vector<vision::VerticalLine> last_;
};

/// The checks across keys of the lamp criteria (each key's own range is its table's).
void checkLampBlobs(const Node& n, const vision::LampBlobOptions& o) {
  if (o.background_window_px != 0 && (o.background_window_px < 3 || o.background_window_px % 2 == 0))
    throw ConfigError(n.where("background_window_px") + " must be 0 (from background_window_rad) or odd, in [3, 255]");
  if (o.max_area_px < o.min_area_px) throw ConfigError(n.where("max_area_px") + " must be >= min_area_px");
  if (o.connectivity != 4 && o.connectivity != 8) throw ConfigError(n.where("connectivity") + " must be 4 or 8");
}

vision::CeilingLightOptions parseLights(const Node& n) {
  if (n.has("background_grey"))
    throw ConfigError(n.where("background_grey") +
                      " was removed: the background is now measured around each blob (a median over"
                      " background_window_px / background_window_rad); delete the key");
  std::vector<std::string> known = config::keysOf(ceilingLightFields(), config::keysOf(lampBlobFields()));
  known.emplace_back("noise_sigma_grey");
  n.rejectUnknownKeysIn(known);
  vision::CeilingLightOptions o;
  config::parseFields(n, o.blobs, lampBlobFields());
  checkLampBlobs(n, o.blobs);
  const double clipped_default = o.max_clipped_elongation;
  config::parseFields(n, o, ceilingLightFields());
  // Not given: at least max_elongation.
  if (!n.has("max_clipped_elongation")) o.max_clipped_elongation = std::max(o.max_elongation, clipped_default);
  if (o.max_clipped_elongation < o.max_elongation)
    throw ConfigError(n.where("max_clipped_elongation") + " must be >= max_elongation");
  // "auto" (or absent): the frame's own noise estimate.
  if (n.has("noise_sigma_grey") && n.getString("noise_sigma_grey") != "auto")
    o.noise_sigma_grey = n.getDouble("noise_sigma_grey", 0.0, 100.0);
  return o;
}

/// The panorama's centre (the camera model's when neither key is given), radii, size and padding.
void parsePanorama(const Node& n, const CameraSetup& cam, vision::PanoramaOptions& p) {
  if (cam.centre_px && !n.has("centre_u_px") && !n.has("centre_v_px")) {
    p.centre_u_px = cam.centre_px->x();
    p.centre_v_px = cam.centre_px->y();
  } else {
    p.centre_u_px = n.getDouble("centre_u_px", -0.5, cam.width_px - 0.5);
    p.centre_v_px = n.getDouble("centre_v_px", -0.5, cam.height_px - 0.5);
  }
  config::parseFields(n, p, panoramaFields(), {"r_min_px", "r_max_px"});
  if (!(p.r_max_px > p.r_min_px + 1.0)) throw ConfigError(n.where("r_max_px") + " must be > r_min_px + 1");
  if (p.rows == 1) throw ConfigError(n.where("rows") + " must be 0 (auto) or >= 2");
  p.pad_columns = static_cast<int>(n.getInt("pad_columns", 2, p.columns / 4, p.pad_columns));  // 2: the seam
  // The panorama's size (rows 0 follows the radii): refused here with the file, not as an
  // allocation of gigabytes when the detector is built.
  if (auto why = vision::validate(p)) throw ConfigError(n.where(n.has("rows") ? "rows" : "r_max_px") + ": " + *why);
}

vision::VerticalLineOptions parseLines(const Node& n, const CameraSetup& cam) {
  std::vector<std::string> known = config::keysOf(panoramaFields(), {"centre_u_px", "centre_v_px"});
  known.emplace_back("pad_columns");
  n.rejectUnknownKeysIn(config::keysOf(verticalLineFields(), known));
  vision::VerticalLineOptions o;
  parsePanorama(n, cam, o.panorama);
  config::parseFields(n, o, verticalLineFields());
  return o;
}

}  // namespace

std::unique_ptr<Detector> makeDetector(const Node& root) {
  root.rejectUnknownKeys({"detector", "max_features", "camera", "ceiling_lights", "vertical_lines"});
  const std::string kind = root.getEnum("detector", {"ceiling_lights", "vertical_lines"});
  const int max_features = static_cast<int>(root.getInt("max_features", 1, 4096, 256));
  CameraSetup cam = parseCamera(root.child("camera"));
  if (kind == "ceiling_lights") {
    if (!cam.model)
      throw ConfigError(root.child("camera").where("model") + " ceiling_lights needs a camera model (not centre_only)");
    const auto opt =
        root.has("ceiling_lights") ? parseLights(root.child("ceiling_lights")) : vision::CeilingLightOptions{};
    return std::make_unique<LightsDetector>(std::move(cam), opt, max_features);
  }
  checkLevelForLines(root.child("camera"), cam);
  const Node n = root.child("vertical_lines");
  const auto opt = parseLines(n, cam);
  return std::make_unique<LinesDetector>(std::move(cam), opt, max_features);
}

vision::VerticalLineOptions verticalLineOptions(const Node& root) {
  const CameraSetup cam = parseCamera(root.child("camera"));
  checkLevelForLines(root.child("camera"), cam);
  return parseLines(root.child("vertical_lines"), cam);
}

CeilingLightSetup ceilingLightSetup(const Node& root) {
  CameraSetup cam = parseCamera(root.child("camera"));
  if (!cam.model)
    throw ConfigError(root.child("camera").where("model") +
                      " ceiling_lights needs a camera model (world or ocamcalib)");
  CeilingLightSetup s;
  s.camera = std::move(cam.model);
  s.mounting = cam.mounting;
  if (root.has("ceiling_lights")) s.options = parseLights(root.child("ceiling_lights"));
  return s;
}

cv::Mat cameraMask(const Node& root) { return parseCamera(root.child("camera")).mask; }

}  // namespace omnislam::features
