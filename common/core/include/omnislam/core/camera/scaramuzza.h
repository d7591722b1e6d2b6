// Scaramuzza / OCamCalib polynomial omnidirectional model (Scaramuzza, Martinelli, Siegwart 2006, as
// in OCamCalib's cam2world / world2cam), with analytic Jacobians, and a pure parser of the
// calib_results.txt text that OCamCalib writes (callers read the file; the core does no I/O).
//
// OCamCalib works in (row, column) order. For a pixel (row, col), 0-based (C convention):
//   [row - xc; col - yc] = A [x_s; y_s],   A = [c d; e 1]          affine sensor -> pixel   [px]
//   rho = hypot(x_s, y_s),   ray_ocam = (x_s, y_s, f(rho)),   f(rho) = sum_i pol[i] rho^i    [px]
//   world2cam: theta = atan(z_ocam / hypot(x_ocam, y_ocam)),  rho ~ sum_i invpol[i] theta^i (a fit)
// calib_results.txt stores the centre as "xc yc" = (row, column), and the size as "height width".
// OCamCalib writes f(0) = pol[0] < 0: the centre pixel sees -z_ocam.
//
// Our axes (docs/user/conventions.md): u = column grows along +x_C, v = row along +y_C, z_C = optical
// axis (up for the project's cameras). With s_z = +1 (catadioptric) or -1 (dioptric):
//   d_C = (y_s, x_s, s_z f(rho)) / norm                       (x_C <- column, y_C <- row)
//  - kCatadioptric (paper 002: camera looking up into a convex mirror): the centre pixel sees the
//    camera itself, i.e. -z_C (down); elevation grows with rho. This map is a reflection of
//    OCamCalib's (x, y, z) frame, as the mirror in the light path makes it.
//  - kDioptric (fish-eye looking up): the centre pixel sees +z_C (up); a proper rotation of
//    OCamCalib's frame, d_C = (y_ocam, x_ocam, -z_ocam).
// The model is used in terms of the angle off the centre ray, beta = atan2(rho, -f(rho)) in [0, pi),
// which must increase strictly with rho over the valid range (checked by validate()).
// project(): beta of the direction -> rho by invpol (initial guess), refined by safeguarded Newton on
// rho cos(beta) + f(rho) sin(beta) = 0, so that unproject(project(d)) is exact (not the invpol fit).
// Valid region: min_radius_px <= rho <= max_radius_px (clipped to the farthest image corner),
// min_elevation_rad <= elevation in C <= max_elevation_rad, and the pixel in the image.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/core/angles.h"
#include "omnislam/core/camera/camera_model.h"

namespace omnislam::camera {

enum class OcamOptics {
  kCatadioptric,  ///< camera looking up into a mirror: centre pixel sees -z_C (s_z = +1)
  kDioptric,      ///< fish-eye lens looking up: centre pixel sees +z_C (s_z = -1)
};

struct ScaramuzzaParams {
  std::vector<double> pol;     ///< f(rho) = sum pol[i] rho^i, OCamCalib "ss" (cam2world); pol[0] < 0 [px]
  std::vector<double> invpol;  ///< rho(theta) = sum invpol[i] theta^i (world2cam), initial guess of project()
  double xc_row_px = 0.0;      ///< distortion centre, ROW, 0-based (OCamCalib xc)
  double yc_col_px = 0.0;      ///< distortion centre, COLUMN, 0-based (OCamCalib yc)
  double c = 1.0;              ///< affine A = [c d; e 1] (OCamCalib c, d, e); c - d e != 0
  double d = 0.0;
  double e = 0.0;
  int width_px = 0;                               ///< image width (columns) [px]; > 0
  int height_px = 0;                              ///< image height (rows) [px]; > 0
  OcamOptics optics = OcamOptics::kCatadioptric;  ///< axis mapping, see the header comment
  double min_radius_px = 0.0;  ///< smallest usable sensor radius rho [px] (e.g. the mirror's dead centre)
  double max_radius_px = std::numeric_limits<double>::infinity();  ///< largest usable rho [px]; clipped to the image
  /// Usable elevation range in C (equal to the robot frame's for a level mounting). Paper 002's
  /// camera: -5 deg .. 65 deg. Default: no restriction.
  double min_elevation_rad = -kPi / 2.0;
  double max_elevation_rad = kPi / 2.0;
};

/// Result of parseOcamCalib: params on success, else an error "line N (field): ...".
struct OcamCalibParseResult {
  std::optional<ScaramuzzaParams> params;
  std::string error;
};

/// Parses the text of OCamCalib's calib_results.txt. Lines starting with '#' and blank lines are
/// skipped; the data lines are, in order: pol ("N c0 .. cN-1"), invpol ("N c0 .. cN-1"), centre
/// ("row col"), affine ("c d e"), size ("height width"). Only the format is checked here (counts,
/// numbers, sizes > 0); ScaramuzzaCamera::validate() checks the model. Valid-region fields and optics
/// keep their defaults. Pure: no file access, locale-independent number parsing.
OcamCalibParseResult parseOcamCalib(const std::string& text);

class ScaramuzzaCamera final : public CameraModel {
 public:
  using Params = ScaramuzzaParams;

  /// Throws std::invalid_argument with validate()'s message when the parameters are not usable.
  explicit ScaramuzzaCamera(const Params& params);

  /// nullopt when usable, else a message naming the field and its accepted range. Monotonicity of
  /// beta(rho) is checked every <= 0.25 px over [min_radius_px, effective max radius].
  static std::optional<std::string> validate(const Params& p);

  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& d_C,
                                         Eigen::Matrix<double, 2, 3>* J_px_d = nullptr) const override;
  std::optional<Eigen::Vector3d> unproject(const Eigen::Vector2d& px,
                                           Eigen::Matrix<double, 3, 2>* J_d_px = nullptr) const override;
  int widthPx() const override { return p_.width_px; }
  int heightPx() const override { return p_.height_px; }
  std::string name() const override { return "scaramuzza-ocamcalib"; }

  const Params& params() const { return p_; }

  /// f(rho) [px] and, when requested, df/drho.
  double fPx(double rho_px, double* df_drho = nullptr) const;
  /// Angle of the ray at sensor radius rho off the centre pixel's ray, atan2(rho, -f(rho)) [rad].
  double offCentreAngle(double rho_px) const;
  /// Exact inverse of offCentreAngle on [min_radius_px, maxRadiusPx()]; nullopt outside its range.
  std::optional<double> radiusOfOffCentreAngle(double beta_rad) const;
  /// Largest usable rho: min(max_radius_px, rho of the farthest image corner) [px].
  double maxRadiusPx() const { return rho_hi_; }

 private:
  static double effectiveMaxRadius(const Params& p);
  double s_z() const { return p_.optics == OcamOptics::kCatadioptric ? 1.0 : -1.0; }

  Params p_;
  double rho_hi_ = 0.0;
  double beta_lo_ = 0.0, beta_hi_ = 0.0;
};

}  // namespace omnislam::camera
