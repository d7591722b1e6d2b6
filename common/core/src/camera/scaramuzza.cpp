// Scaramuzza / OCamCalib polynomial model: projection, exact inverse, Jacobians, validation, and the
// pure parser of calib_results.txt text.
#include "omnislam/core/camera/scaramuzza.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string_view>

namespace omnislam::camera {

namespace {

std::string str(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", x);  // formatting only, no I/O
  return buf;
}

// G maps sensor coordinates q = (y_s, x_s) (column, row order) to pixel offsets (u - yc, v - xc):
//   u - yc = q1 + e q2,  v - xc = d q1 + c q2   (OCamCalib: row - xc = c x_s + d y_s, col - yc = e x_s + y_s)
Eigen::Matrix2d sensorToPixel(const ScaramuzzaParams& p) {
  Eigen::Matrix2d G;
  G << 1.0, p.e, p.d, p.c;
  return G;
}

// Q = G^-1 maps pixel offsets (u - yc, v - xc) to q; det G = c - d e (OCamCalib's 1 / invdet).
Eigen::Matrix2d pixelToSensor(const ScaramuzzaParams& p) {
  Eigen::Matrix2d Q;
  Q << p.c, -p.e, -p.d, 1.0;
  return Q / (p.c - p.d * p.e);
}

}  // namespace

// Parts of ScaramuzzaCamera::validate.
namespace {

/// Every coefficient and the other real parameters finite, and pol[0] = f(0) < 0.
std::optional<std::string> checkFinite(const ScaramuzzaParams& p) {
  for (std::size_t i = 0; i < p.pol.size(); ++i) {
    if (!std::isfinite(p.pol[i])) return "pol[" + std::to_string(i) + "] must be finite";
  }
  for (std::size_t i = 0; i < p.invpol.size(); ++i) {
    if (!std::isfinite(p.invpol[i])) return "invpol[" + std::to_string(i) + "] must be finite";
  }
  if (!(p.pol[0] < 0.0)) {
    return "pol[0] = f(0) must be < 0 (OCamCalib convention: the centre pixel sees -z_ocam; got " + str(p.pol[0]) + ")";
  }
  const struct {
    const char* name;
    double v;
  } finite[] = {{"xc_row_px", p.xc_row_px},
                {"yc_col_px", p.yc_col_px},
                {"c", p.c},
                {"d", p.d},
                {"e", p.e},
                {"min_radius_px", p.min_radius_px},
                {"min_elevation_rad", p.min_elevation_rad},
                {"max_elevation_rad", p.max_elevation_rad}};
  for (const auto& f : finite) {
    if (!std::isfinite(f.v)) return std::string(f.name) + " must be finite (got " + str(f.v) + ")";
  }
  return std::nullopt;
}

/// The largest |f(rho)| a camera may have [px]: f is the distance of the unit sphere's image plane in
/// pixels, a few hundred for a fish-eye; at 1e9 px the whole image would fall within 1e-3 rad of the
/// axis (1e6 px / 1e9 px), and the ray (q, f) would lose its q in floating point.
constexpr double kMaxAbsFPx = 1e9;

/// beta(rho) = atan2(rho, -f) increases strictly on [min_radius_px, rho_hi] (<=> rho f'(rho) - f(rho)
/// > 0) and |f| <= kMaxAbsFPx, checked at four samples per pixel (rho_hi <= 1e6 px: the caller caps the count).
std::optional<std::string> checkMonotonic(const ScaramuzzaParams& p, double rho_hi) {
  const int n = std::max(2, static_cast<int>(std::ceil(4.0 * (rho_hi - p.min_radius_px))));
  for (int i = 0; i <= n; ++i) {
    const double rho = p.min_radius_px + (rho_hi - p.min_radius_px) * i / n;
    double f = 0.0, df = 0.0;
    for (std::size_t k = p.pol.size(); k-- > 0;) {
      df = df * rho + f;
      f = f * rho + p.pol[k];
    }
    if (!(std::abs(f) <= kMaxAbsFPx)) {  // found by tests/fuzz (regressions/ocamcalib): pol[2] = 2e173
      return "pol: |f(rho)| must stay within " + str(kMaxAbsFPx) + " px on [min_radius_px, " + str(rho_hi) +
             "] px (a focal length of more would make the whole image see one direction); it is " + str(f) +
             " at rho = " + str(rho) + " px";
    }
    if (!(rho * df - f > 0.0)) {
      return "pol: the ray angle atan2(rho, -f(rho)) must increase strictly with rho on [min_radius_px, " +
             str(rho_hi) + "] px; it does not at rho = " + str(rho) +
             " px (lower max_radius_px to the polynomial's usable range)";
    }
  }
  return std::nullopt;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Model

double ScaramuzzaCamera::effectiveMaxRadius(const Params& p) {
  const Eigen::Matrix2d Q = pixelToSensor(p);
  double rho_corner = 0.0;
  for (const double u : {-0.5, p.width_px - 0.5}) {
    for (const double v : {-0.5, p.height_px - 0.5}) {
      rho_corner = std::max(rho_corner, (Q * Eigen::Vector2d(u - p.yc_col_px, v - p.xc_row_px)).norm());
    }
  }
  return std::min(p.max_radius_px, rho_corner);
}

std::optional<std::string> ScaramuzzaCamera::validate(const Params& p) {
  if (p.width_px <= 0) return "width_px must be > 0 (got " + std::to_string(p.width_px) + ")";
  if (p.height_px <= 0) return "height_px must be > 0 (got " + std::to_string(p.height_px) + ")";
  if (p.pol.empty() || p.pol.size() > 64)
    return "pol must have 1 to 64 coefficients (got " + std::to_string(p.pol.size()) + ")";
  if (p.invpol.empty() || p.invpol.size() > 64) {
    return "invpol must have 1 to 64 coefficients (got " + std::to_string(p.invpol.size()) + ")";
  }
  if (auto why = checkFinite(p)) return why;
  const double det = p.c - p.d * p.e;
  if (!(std::abs(det) > 1e-9)) {
    return "affine c, d, e: c - d*e must be non-zero so that A = [c d; e 1] is invertible (got " + str(det) + ")";
  }
  if (!(p.min_radius_px >= 0.0)) return "min_radius_px must be >= 0 (got " + str(p.min_radius_px) + ")";
  if (!(p.max_radius_px > p.min_radius_px)) {
    return "max_radius_px must be > min_radius_px = " + str(p.min_radius_px) + " (got " + str(p.max_radius_px) + ")";
  }
  if (!(p.min_elevation_rad >= -kPi / 2.0 && p.max_elevation_rad <= kPi / 2.0 &&
        p.min_elevation_rad < p.max_elevation_rad)) {
    return "min_elevation_rad, max_elevation_rad must satisfy -pi/2 <= min < max <= pi/2 (got " +
           str(p.min_elevation_rad) + ", " + str(p.max_elevation_rad) + ")";
  }
  const double rho_hi = effectiveMaxRadius(p);
  if (!(rho_hi > p.min_radius_px)) {
    return "min_radius_px must be < the usable max radius min(max_radius_px, farthest image corner) = " + str(rho_hi) +
           " px (got " + str(p.min_radius_px) + ")";
  }
  // beta(rho) = atan2(rho, -f) increases strictly  <=>  rho f'(rho) - f(rho) > 0.
  // Four samples per pixel, capped: a near-singular affine part makes rho_hi ~1e10 px, and the
  // count overflowed int (undefined; on x86 it became 2 and a non-monotonic polynomial passed).
  if (!(rho_hi <= 1e6))
    return "the usable max radius " + str(rho_hi) + " px is beyond 1e6 px (a near-singular affine c, d, e?)";
  return checkMonotonic(p, rho_hi);
}

ScaramuzzaCamera::ScaramuzzaCamera(const Params& params) : p_(params) {
  if (const auto err = validate(p_)) throw std::invalid_argument("ScaramuzzaParams: " + *err);
  rho_hi_ = effectiveMaxRadius(p_);
  beta_lo_ = offCentreAngle(p_.min_radius_px);
  beta_hi_ = offCentreAngle(rho_hi_);
}

double ScaramuzzaCamera::fPx(double rho_px, double* df_drho) const {
  double f = 0.0, df = 0.0;
  for (std::size_t k = p_.pol.size(); k-- > 0;) {  // Horner for f and f'
    df = df * rho_px + f;
    f = f * rho_px + p_.pol[k];
  }
  if (df_drho) *df_drho = df;
  return f;
}

double ScaramuzzaCamera::offCentreAngle(double rho_px) const { return std::atan2(rho_px, -fPx(rho_px)); }

std::optional<double> ScaramuzzaCamera::radiusOfOffCentreAngle(double beta_rad) const {
  constexpr double kTol = 1e-12;
  if (!(beta_rad >= beta_lo_ - kTol && beta_rad <= beta_hi_ + kTol)) return std::nullopt;
  double lo = p_.min_radius_px, hi = rho_hi_;
  if (beta_rad <= beta_lo_) return lo;
  if (beta_rad >= beta_hi_) return hi;
  // Initial guess from OCamCalib's inverse polynomial in theta = beta - pi/2 (world2cam).
  const double theta = beta_rad - kPi / 2.0;
  double rho = 0.0;
  for (std::size_t k = p_.invpol.size(); k-- > 0;) rho = rho * theta + p_.invpol[k];
  if (!(rho > lo && rho < hi)) rho = 0.5 * (lo + hi);
  // g(rho) = rho cos(beta) + f(rho) sin(beta) = R sin(beta(rho) - beta): negative below the root.
  const double cb = std::cos(beta_rad), sb = std::sin(beta_rad);
  for (int it = 0; it < 100; ++it) {
    double df = 0.0;
    const double g = rho * cb + fPx(rho, &df) * sb;
    if (g == 0.0) break;
    (g < 0.0 ? lo : hi) = rho;
    double next = rho - g / (cb + df * sb);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double step = std::abs(next - rho);
    rho = next;
    if (step <= 1e-13 * std::max(1.0, rho) || hi - lo <= 1e-13 * std::max(1.0, rho)) break;
  }
  return rho;
}

std::optional<Eigen::Vector2d> ScaramuzzaCamera::project(const Eigen::Vector3d& d_C,
                                                         Eigen::Matrix<double, 2, 3>* J_px_d) const {
  const double n = d_C.norm();
  if (!(n > 0.0) || !std::isfinite(n)) return std::nullopt;
  const double nxy = std::hypot(d_C.x(), d_C.y());
  const double el = std::atan2(d_C.z(), nxy);
  if (el < p_.min_elevation_rad || el > p_.max_elevation_rad) return std::nullopt;
  const double m = -s_z() * d_C.z();  // component along the centre pixel's ray
  const double beta = std::atan2(nxy, m);
  const std::optional<double> rho = radiusOfOffCentreAngle(beta);
  if (!rho) return std::nullopt;
  const Eigen::Vector2d w = nxy > 0.0 ? Eigen::Vector2d(d_C.x() / nxy, d_C.y() / nxy) : Eigen::Vector2d::Zero();
  const Eigen::Matrix2d G = sensorToPixel(p_);
  const Eigen::Vector2d px = Eigen::Vector2d(p_.yc_col_px, p_.xc_row_px) + G * (*rho * w);
  if (!inImage(px)) return std::nullopt;
  if (J_px_d) {
    // q = rho(beta) w;  d(rho)/d(beta) = (rho^2 + f^2) / (rho f' - f).
    double df = 0.0;
    const double f = fPx(*rho, &df);
    const double drho_dbeta = (*rho * *rho + f * f) / (*rho * df - f);
    Eigen::Matrix<double, 2, 3> J_q_d;  // 2x3
    if (nxy > 0.0) {
      // d(beta)/d(d) = [m w^T, s_z nxy] / n^2 (1x3);  d(w)/d(d) = [(I - w w^T) / nxy, 0] (2x3)
      const Eigen::RowVector3d J_beta_d = Eigen::RowVector3d(m * w.x(), m * w.y(), s_z() * nxy) / (n * n);
      J_q_d = w * (drho_dbeta * J_beta_d);
      J_q_d.leftCols<2>() += (*rho / nxy) * (Eigen::Matrix2d::Identity() - w * w.transpose());
    } else {
      // On the centre ray q = rho'(0) (x, y) / n to first order (pol[1] = 0 as OCamCalib fits it).
      J_q_d.setZero();
      J_q_d.leftCols<2>() = (drho_dbeta / n) * Eigen::Matrix2d::Identity();
    }
    *J_px_d = G * J_q_d;  // 2x2 * 2x3 = 2x3
  }
  return px;
}

std::optional<Eigen::Vector3d> ScaramuzzaCamera::unproject(const Eigen::Vector2d& px,
                                                           Eigen::Matrix<double, 3, 2>* J_d_px) const {
  if (!inImage(px)) return std::nullopt;
  const Eigen::Matrix2d Q = pixelToSensor(p_);  // pixel offset -> q = (y_s, x_s)
  const Eigen::Vector2d q = Q * Eigen::Vector2d(px.x() - p_.yc_col_px, px.y() - p_.xc_row_px);
  const double rho = q.norm();
  if (rho < p_.min_radius_px - 1e-9 || rho > rho_hi_ + 1e-9) return std::nullopt;
  double df = 0.0;
  const double f = fPx(rho, &df);
  const Eigen::Vector3d m(q.x(), q.y(), s_z() * f);
  const double mn = m.norm();
  const Eigen::Vector3d d_C = m / mn;
  const double el = std::atan2(d_C.z(), std::hypot(d_C.x(), d_C.y()));
  if (el < p_.min_elevation_rad || el > p_.max_elevation_rad) return std::nullopt;
  if (J_d_px) {
    const Eigen::Vector2d w = rho > 0.0 ? Eigen::Vector2d(q / rho) : Eigen::Vector2d::Zero();
    Eigen::Matrix<double, 3, 2> J_m_q;  // 3x2: m = (q, s_z f(|q|))
    J_m_q.topRows<2>().setIdentity();
    J_m_q.row(2) = s_z() * df * w.transpose();
    const Eigen::Matrix3d J_d_m = (Eigen::Matrix3d::Identity() - d_C * d_C.transpose()) / mn;  // 3x3
    *J_d_px = J_d_m * J_m_q * Q;                                                               // 3x3 * 3x2 * 2x2 = 3x2
  }
  return d_C;
}

// ---------------------------------------------------------------------------------------------
// Parser of calib_results.txt

namespace {

struct DataLine {
  int number = 0;  // 1-based line number in the text
  std::vector<std::string_view> tokens;
};

std::vector<DataLine> dataLines(const std::string& text) {
  std::vector<DataLine> lines;
  std::string_view rest(text);
  int number = 0;
  while (!rest.empty()) {
    const std::size_t eol = rest.find('\n');
    std::string_view line = rest.substr(0, eol);
    rest = eol == std::string_view::npos ? std::string_view() : rest.substr(eol + 1);
    ++number;
    DataLine dl{number, {}};
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
      std::size_t j = i;
      while (j < line.size() && !(line[j] == ' ' || line[j] == '\t' || line[j] == '\r')) ++j;
      if (j > i) dl.tokens.push_back(line.substr(i, j - i));
      i = j;
    }
    if (dl.tokens.empty() || dl.tokens.front().front() == '#') continue;
    lines.push_back(std::move(dl));
  }
  return lines;
}

template <typename T>
bool toNumber(std::string_view tok, T& out) {
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  const char* end = tok.data() + tok.size();
  const auto res = std::from_chars(tok.data(), end, out);
  return res.ec == std::errc() && res.ptr == end;
}

/// A polynomial's line "N c0 c1 ... cN-1" into coeffs; nothing, or why it is refused.
std::optional<std::string> readPolynomial(const DataLine& l, std::vector<double>& coeffs) {
  int count = 0;
  if (!toNumber(l.tokens[0], count) || count < 1 || count > 64)
    return "the coefficient count '" + std::string(l.tokens[0]) + "' must be an integer in [1, 64]";
  if (l.tokens.size() != static_cast<std::size_t>(count) + 1)
    return "the count says " + std::to_string(count) + " coefficients, found " + std::to_string(l.tokens.size() - 1);
  coeffs.resize(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    if (!toNumber(l.tokens[static_cast<std::size_t>(i) + 1], coeffs[static_cast<std::size_t>(i)]))
      return "coefficient " + std::to_string(i) + " '" + std::string(l.tokens[static_cast<std::size_t>(i) + 1]) +
             "' is not a number";
  }
  return std::nullopt;
}

}  // namespace

OcamCalibParseResult parseOcamCalib(const std::string& text) {
  OcamCalibParseResult result;
  const char* const fields[] = {"pol", "invpol", "centre", "affine", "size"};
  const char* const formats[] = {"N c0 .. cN-1", "N c0 .. cN-1", "row col", "c d e", "height width"};
  const std::vector<DataLine> lines = dataLines(text);
  const auto where = [&fields](const DataLine& l, int field) {
    return "line " + std::to_string(l.number) + " (" + fields[field] + "): ";
  };
  if (lines.size() < 5) {
    const std::size_t k = lines.size();
    result.error = "missing data line for field '" + std::string(fields[k]) + "' (\"" + formats[k] + "\"): found " +
                   std::to_string(k) + " of 5 data lines";
    return result;
  }
  if (lines.size() > 5) {
    result.error = "line " + std::to_string(lines[5].number) + ": unexpected data after the image size line";
    return result;
  }
  ScaramuzzaParams p;
  // pol and invpol: "N c0 c1 ... cN-1"
  for (int field = 0; field < 2; ++field) {
    if (auto why = readPolynomial(lines[field], field == 0 ? p.pol : p.invpol)) {
      result.error = where(lines[field], field) + *why;
      return result;
    }
  }
  // centre "row col" and affine "c d e"
  const auto readDoubles = [&](int field, std::initializer_list<double*> outs) -> bool {
    const DataLine& l = lines[static_cast<std::size_t>(field)];
    if (l.tokens.size() != outs.size()) {
      result.error = where(l, field) + "expected " + std::to_string(outs.size()) + " numbers (\"" + formats[field] +
                     "\"), found " + std::to_string(l.tokens.size());
      return false;
    }
    std::size_t i = 0;
    for (double* out : outs) {
      if (!toNumber(l.tokens[i], *out)) {
        result.error = where(l, field) + "'" + std::string(l.tokens[i]) + "' is not a number";
        return false;
      }
      ++i;
    }
    return true;
  };
  if (!readDoubles(2, {&p.xc_row_px, &p.yc_col_px})) return result;
  if (!readDoubles(3, {&p.c, &p.d, &p.e})) return result;
  // size "height width"
  const DataLine& l = lines[4];
  if (l.tokens.size() != 2 || !toNumber(l.tokens[0], p.height_px) || !toNumber(l.tokens[1], p.width_px) ||
      p.height_px <= 0 || p.width_px <= 0) {
    result.error = where(l, 4) + "expected two positive integers \"height width\"";
    return result;
  }
  result.params = std::move(p);
  return result;
}

}  // namespace omnislam::camera
