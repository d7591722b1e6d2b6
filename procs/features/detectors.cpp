// Detectors of omnislam-features: see detectors.h.
#include "detectors.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "omnislam/config/world_config.h"
#include "omnislam/core/angles.h"
#include "omnislam/core/camera/pajdla_bakstein.h"
#include "omnislam/core/camera/scaramuzza.h"
#include "omnislam/vision/annotate.h"
#include "omnislam/vision/ceiling_lights.h"
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
};

camera::CameraMounting parseMounting(const Node& m) {
  m.rejectUnknownKeys({"x_m", "y_m", "z_m", "yaw_deg"});
  camera::CameraMounting out;
  out.x_m = m.getDouble("x_m", -10.0, 10.0, 0.0);
  out.y_m = m.getDouble("y_m", -10.0, 10.0, 0.0);
  out.z_m = m.getDouble("z_m", -10.0, 10.0);
  out.yaw_rad = deg2rad(m.getDouble("yaw_deg", -180.0, 180.0, 0.0));
  return out;
}

CameraSetup parseCamera(const Node& c) {
  c.rejectUnknownKeys({"model", "world", "file", "optics", "min_elevation_deg", "max_elevation_deg", "min_radius_px",
                       "max_radius_px", "width_px", "height_px", "mounting"});
  CameraSetup s;
  const std::string model = c.getEnum("model", {"world", "ocamcalib", "centre_only"});
  if (model == "world") {
    const sim::World w = config::loadWorld(c.getPath("world"));
    s.model = sim::makeCamera(w.camera);  // the world's model: Pajdla-Bakstein or Scaramuzza
    s.mounting = c.has("mounting") ? parseMounting(c.child("mounting")) : w.camera.mounting;
    s.centre_px = sim::cameraCentrePx(w.camera);
    s.description = s.model->name() + " camera of world '" + w.name + "'";
  } else if (model == "ocamcalib") {
    const std::string path = c.getPath("file");
    std::ifstream f(path);
    if (!f) throw ConfigError(c.where("file") + " cannot read '" + path + "'");
    std::stringstream ss;
    ss << f.rdbuf();
    auto parsed = camera::parseOcamCalib(ss.str());
    if (!parsed.params) throw ConfigError(c.where("file") + " '" + path + "': " + parsed.error);
    camera::ScaramuzzaParams p = *parsed.params;
    p.optics = c.getEnum("optics", {"catadioptric", "dioptric"}, "catadioptric") == "catadioptric"
                   ? camera::OcamOptics::kCatadioptric
                   : camera::OcamOptics::kDioptric;
    p.min_elevation_rad = deg2rad(c.getDouble("min_elevation_deg", -90.0, 90.0, -90.0));
    p.max_elevation_rad = deg2rad(c.getDouble("max_elevation_deg", -90.0, 90.0, 90.0));
    p.min_radius_px = c.getDouble("min_radius_px", 0.0, 1e5, 0.0);
    if (c.has("max_radius_px")) p.max_radius_px = c.getDouble("max_radius_px", 1.0, 1e5);
    if (auto why = camera::ScaramuzzaCamera::validate(p)) throw ConfigError(c.where("file") + " " + *why);
    s.model = std::make_unique<camera::ScaramuzzaCamera>(p);
    s.mounting = parseMounting(c.child("mounting"));
    s.centre_px = Eigen::Vector2d(p.yc_col_px, p.xc_row_px);
    s.description = "OCamCalib camera from " + path;
  } else {
    s.mounting = parseMounting(c.child("mounting"));
    s.description = "centre-only geometry (azimuth = image angle about the panorama centre)";
  }
  if (s.model) {
    s.width_px = s.model->widthPx();
    s.height_px = s.model->heightPx();
  } else {
    s.width_px = static_cast<int>(c.getInt("width_px", 1, 16384));
    s.height_px = static_cast<int>(c.getInt("height_px", 1, 16384));
  }
  return s;
}

// Reads only the image's header fields (omnislam-features also runs it on vision::HeaderProbe, the
// dimensions of an encoded image before decoding). The size is judged first: a frame of another
// camera is named as such whatever its format; the message gives what came and what is needed.
std::string checkSizeAndFormat(const cv::Mat& img, int w, int h, bool colour_ok) {
  if (img.empty()) return "empty image";
  const bool size_ok = img.cols == w && img.rows == h;
  if (size_ok && img.depth() == CV_8U && (img.channels() == 1 || (colour_ok && img.channels() == 3))) return {};
  static const char* const kDepth[] = {"8-bit", "8-bit signed", "16-bit", "16-bit signed", "32-bit integer",
                                       "32-bit float", "64-bit float", "16-bit float"};
  auto dims = [](int cols, int rows) { return std::to_string(cols) + "x" + std::to_string(rows); };
  return (size_ok ? std::string("format") : "size " + dims(img.cols, img.rows)) + " does not match the camera (received " +
         dims(img.cols, img.rows) + ", " + std::to_string(img.channels()) + (img.channels() == 1 ? " channel, " : " channels, ") +
         kDepth[img.depth()] + "; the camera needs " + dims(w, h) + ", 8-bit " + (colour_ok ? "grey or BGR)" : "grey)");
}

class LightsDetector final : public Detector {
 public:
  LightsDetector(CameraSetup cam, const vision::CeilingLightOptions& opt, int max_features)
      : cam_(std::move(cam)), det_(*cam_.model, cam_.mounting, opt), max_features_(max_features) {}
  std::string name() const override { return "ceiling_lights"; }
  std::optional<std::string> check(const cv::Mat& img) const override {
    auto why = checkSizeAndFormat(img, cam_.width_px, cam_.height_px, false);
    return why.empty() ? std::nullopt : std::optional<std::string>(why);
  }
  std::vector<feature_t> detect(const cv::Mat& img) const override {
    auto lights = det_.detect(img);
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
      // Mean grey of the blob (the IR image is grey): mass / area + background.
      const float mean = static_cast<float>(L.blob.mass / std::max(1, L.blob.area_px) + det_.options().blobs.background_grey);
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
  mutable std::vector<vision::CeilingLight> last_;
};

class LinesDetector final : public Detector {
 public:
  LinesDetector(CameraSetup cam, const vision::VerticalLineOptions& opt, int max_features)
      : cam_(std::move(cam)),
        det_(opt, cam_.width_px, cam_.height_px, cam_.model.get(), cam_.mounting),
        max_features_(max_features) {}
  std::string name() const override { return "vertical_lines"; }
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
    return s.str();
  }

 private:
  CameraSetup cam_;
  vision::VerticalLineDetector det_;
  int max_features_;
  mutable std::vector<vision::VerticalLine> last_;
};

vision::CeilingLightOptions parseLights(const Node& n) {
  n.rejectUnknownKeys({"threshold_grey", "background_grey", "min_area_px", "max_area_px", "connectivity",
                       "max_elongation", "noise_sigma_grey", "pixel_sigma_floor_px"});
  vision::CeilingLightOptions o;
  o.blobs.threshold_grey = static_cast<int>(n.getInt("threshold_grey", 0, 254, o.blobs.threshold_grey));
  o.blobs.background_grey = n.getDouble("background_grey", 0.0, 254.0, o.blobs.background_grey);
  o.blobs.min_area_px = static_cast<int>(n.getInt("min_area_px", 1, 1'000'000, o.blobs.min_area_px));
  o.blobs.max_area_px = static_cast<int>(n.getInt("max_area_px", 1, 10'000'000, o.blobs.max_area_px));
  if (o.blobs.max_area_px < o.blobs.min_area_px) throw ConfigError(n.where("max_area_px") + " must be >= min_area_px");
  o.blobs.connectivity = static_cast<int>(n.getInt("connectivity", 4, 8, o.blobs.connectivity));
  if (o.blobs.connectivity != 4 && o.blobs.connectivity != 8) throw ConfigError(n.where("connectivity") + " must be 4 or 8");
  o.max_elongation = n.getDouble("max_elongation", 1.0, 100.0, o.max_elongation);
  o.noise_sigma_grey = n.getDouble("noise_sigma_grey", 0.0, 100.0, o.noise_sigma_grey);
  o.pixel_sigma_floor_px = n.getDouble("pixel_sigma_floor_px", 1e-3, 100.0, o.pixel_sigma_floor_px);
  return o;
}

vision::VerticalLineOptions parseLines(const Node& n, const CameraSetup& cam) {
  n.rejectUnknownKeys({"centre_u_px", "centre_v_px", "r_min_px", "r_max_px", "columns", "rows", "pad_columns",
                       "edge_threshold", "min_run_rows", "max_gap_rows", "merge_columns", "merge_gap_rows",
                       "min_length_rows", "max_drift_columns", "max_rms_columns", "colour_offset_columns",
                       "colour_width_columns", "pixel_sigma_px"});
  vision::VerticalLineOptions o;
  auto& p = o.panorama;
  if (cam.centre_px && !n.has("centre_u_px") && !n.has("centre_v_px")) {
    p.centre_u_px = cam.centre_px->x();
    p.centre_v_px = cam.centre_px->y();
  } else {
    p.centre_u_px = n.getDouble("centre_u_px", -0.5, cam.width_px - 0.5);
    p.centre_v_px = n.getDouble("centre_v_px", -0.5, cam.height_px - 0.5);
  }
  p.r_min_px = n.getDouble("r_min_px", 0.0, 1e5);
  p.r_max_px = n.getDouble("r_max_px", 1.0, 1e5);
  if (!(p.r_max_px > p.r_min_px + 1.0)) throw ConfigError(n.where("r_max_px") + " must be > r_min_px + 1");
  p.columns = static_cast<int>(n.getInt("columns", 36, 20000, p.columns));
  p.rows = static_cast<int>(n.getInt("rows", 0, 20000, p.rows));
  if (p.rows == 1) throw ConfigError(n.where("rows") + " must be 0 (auto) or >= 2");
  p.pad_columns = static_cast<int>(n.getInt("pad_columns", 2, p.columns / 4, p.pad_columns));  // 2: the seam
  // The panorama's size (rows 0 follows the radii): refused here with the file, not as an
  // allocation of gigabytes when the detector is built.
  if (auto why = vision::validate(p)) throw ConfigError(n.where(n.has("rows") ? "rows" : "r_max_px") + ": " + *why);
  o.edge_threshold = static_cast<int>(n.getInt("edge_threshold", 1, 1020, o.edge_threshold));
  o.min_run_rows = static_cast<int>(n.getInt("min_run_rows", 1, 100000, o.min_run_rows));
  o.max_gap_rows = static_cast<int>(n.getInt("max_gap_rows", 0, 100000, o.max_gap_rows));
  o.merge_columns = static_cast<int>(n.getInt("merge_columns", 0, 20, o.merge_columns));
  o.merge_gap_rows = static_cast<int>(n.getInt("merge_gap_rows", 0, 100000, o.merge_gap_rows));
  o.min_length_rows = static_cast<int>(n.getInt("min_length_rows", 1, 100000, o.min_length_rows));
  o.max_drift_columns = n.getDouble("max_drift_columns", 0.01, 1000.0, o.max_drift_columns);
  o.max_rms_columns = n.getDouble("max_rms_columns", 0.01, 1000.0, o.max_rms_columns);
  o.colour_offset_columns = static_cast<int>(n.getInt("colour_offset_columns", 1, 1000, o.colour_offset_columns));
  o.colour_width_columns = static_cast<int>(n.getInt("colour_width_columns", 1, 1000, o.colour_width_columns));
  o.pixel_sigma_px = n.getDouble("pixel_sigma_px", 1e-3, 100.0, o.pixel_sigma_px);
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
      throw ConfigError(root.child("camera").where("model") + " ceiling_lights needs a camera model (world or ocamcalib)");
    const auto opt = root.has("ceiling_lights") ? parseLights(root.child("ceiling_lights")) : vision::CeilingLightOptions{};
    return std::make_unique<LightsDetector>(std::move(cam), opt, max_features);
  }
  const Node n = root.child("vertical_lines");
  const auto opt = parseLines(n, cam);
  return std::make_unique<LinesDetector>(std::move(cam), opt, max_features);
}

vision::VerticalLineOptions verticalLineOptions(const Node& root) {
  return parseLines(root.child("vertical_lines"), parseCamera(root.child("camera")));
}

}  // namespace omnislam::features
