// The world camera's options tables (see world_camera_table.h): one row per key.
#include "omnislam/config/world_camera_table.h"

#include "omnislam/config/options_parse.h"

namespace omnislam::config {

namespace {

using options::Bounds;
using options::integer;
using options::real;
constexpr Bounds kC = Bounds::kClosed;

}  // namespace

// One row per key: not reformatted.
// clang-format off
const std::vector<options::Field<camera::PajdlaBaksteinParams>>& pajdlaBaksteinFields() {
  using P = camera::PajdlaBaksteinParams;
  static const std::vector<options::Field<P>> t{
      real<P>("a_px", &P::a_px, "a_px", "px", -1e5, 1e5, kC, "coefficient of tan(zeta / b) (paper 000 eq. 1)"),
      real<P>("b", &P::b, "b", "", 1e-3, 1e3, kC, "divisor of zeta in tan; > 2 max_zenith / pi"),
      real<P>("c_px", &P::c_px, "c_px", "px", -1e5, 1e5, kC, "coefficient of sin(zeta / d)"),
      real<P>("d", &P::d, "d", "", 1e-3, 1e3, kC, "divisor of zeta in sin"),
      real<P>("u0_px", &P::u0_px, "u0_px", "px", -1e4, 1e5, kC, "column of the optical axis"),
      real<P>("v0_px", &P::v0_px, "v0_px", "px", -1e4, 1e5, kC, "row of the optical axis"),
      real<P>("beta", &P::beta, "beta", "", 0.1, 10, kC, "pixel aspect ratio (scales row offsets)"),
      integer<P>("width_px", &P::width_px, "width_px", 16, 8192, "image width"),
      integer<P>("height_px", &P::height_px, "height_px", 16, 8192, "image height"),
      real<P>("max_zenith_deg", &P::max_zenith_rad, "max_zenith_rad", "deg", 1, 179, kC, "half field of view; then the model's own checks (camera-models.md, \"Validation\")", true),
  };
  return t;
}

const std::vector<options::Field<camera::ScaramuzzaParams>>& scaramuzzaFields() {
  using S = camera::ScaramuzzaParams;
  static const std::vector<options::Field<S>> t{
      real<S>("affine_c", &S::c, "c", "", 0.5, 2, kC, "OCamCalib's affine matrix [c d; e 1]"),
      real<S>("affine_d", &S::d, "d", "", -0.5, 0.5, kC, "OCamCalib's affine matrix [c d; e 1]"),
      real<S>("affine_e", &S::e, "e", "", -0.5, 0.5, kC, "OCamCalib's affine matrix [c d; e 1]"),
      real<S>("min_radius_px", &S::min_radius_px, "min_radius_px", "px", 0, 1e4, kC, "smallest usable sensor radius"),
      real<S>("max_radius_px", &S::max_radius_px, "max_radius_px", "px", 1, 1e4, kC, "largest usable sensor radius (inf: none, the image's)"),
      real<S>("min_elevation_deg", &S::min_elevation_rad, "min_elevation_rad", "deg", -90, 90, kC, "usable elevation band, lower end (paper 002: -5)", true),
      real<S>("max_elevation_deg", &S::max_elevation_rad, "max_elevation_rad", "deg", -90, 90, kC, "usable elevation band, upper end (paper 002: 65); > min_elevation_deg", true),
  };
  return t;
}
// clang-format on

std::string worldCameraKeysMarkdown() {
  return markdownHeader() + markdownRows("camera.", pajdlaBaksteinFields(), camera::PajdlaBaksteinParams{});
}

std::string worldScaramuzzaKeysMarkdown() {
  return markdownHeader() + markdownRows("camera.", scaramuzzaFields(), camera::ScaramuzzaParams{});
}

}  // namespace omnislam::config
