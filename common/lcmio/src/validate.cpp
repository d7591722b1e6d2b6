// Validation of decoded messages: see validate.h.
#include "omnislam/lcmio/validate.h"

#include <algorithm>
#include <cmath>

namespace omnislam::lcmio {
namespace {

bool finite(double v) { return std::isfinite(v); }

template <size_t N>
bool allFinite(const double (&a)[N]) {
  for (double v : a)
    if (!finite(v)) return false;
  return true;
}
template <size_t N, size_t M>
bool allFinite(const double (&a)[N][M]) {
  for (const auto& row : a)
    if (!allFinite(row)) return false;
  return true;
}

// A message built in code (a producer checking its own output) can hold a count that its array
// does not: decoded messages always agree, but validate must not index past the array either way.
std::optional<std::string> countMismatch(const char* field, int64_t count, size_t array_size) {
  if (static_cast<size_t>(count) == array_size) return std::nullopt;
  return std::string(field) + " " + std::to_string(count) + " != its array's size " + std::to_string(array_size);
}

std::optional<std::string> checkTime(int64_t utime, int64_t seq) {
  if (utime < 0) return "negative utime " + std::to_string(utime);
  if (utime > kMaxUtime) return "utime " + std::to_string(utime) + " beyond 2^62 us (a corrupted field)";
  if (seq < 0) return "negative seq " + std::to_string(seq);
  return std::nullopt;
}

}  // namespace

std::optional<std::string> validate(const image_t& m, const Limits& lim) {
  if (auto e = checkTime(m.utime, m.seq)) return e;
  if (m.width <= 0 || m.height <= 0 || m.width > lim.max_image_side_px || m.height > lim.max_image_side_px)
    return "image size " + std::to_string(m.width) + "x" + std::to_string(m.height) + " outside 1.." +
           std::to_string(lim.max_image_side_px);
  if (m.size < 0 || m.size > lim.max_image_bytes || static_cast<size_t>(m.size) != m.data.size())
    return "image data size " + std::to_string(m.size) + " invalid";
  int channels = 0;
  switch (m.pixel_format) {
    case image_t::FORMAT_GRAY8: channels = 1; break;
    case image_t::FORMAT_RGB8:
    case image_t::FORMAT_BGR8: channels = 3; break;
    case image_t::FORMAT_JPEG:
    case image_t::FORMAT_PNG: channels = 0; break;
    default: return "unknown pixel_format " + std::to_string(m.pixel_format);
  }
  if (channels > 0) {
    if (m.row_stride < m.width * channels) return "row_stride " + std::to_string(m.row_stride) + " < width * channels";
    if (static_cast<int64_t>(m.row_stride) * m.height != m.size)
      return "size " + std::to_string(m.size) + " != row_stride * height";
  } else if (m.size == 0) {
    return "empty compressed image";
  } else if (m.row_stride != 0) {
    return "row_stride " + std::to_string(m.row_stride) + " must be 0 for a compressed image";
  }
  return std::nullopt;
}

/// A covariance matrix as the contract allows it: finite, symmetric (to rounding) and with no
/// negative variance (all zero for ground truth). "" when it is.
template <size_t N>
std::string covarianceProblem(const double (&c)[N][N]) {
  if (!allFinite(c)) return "non-finite covariance";
  double scale = 0.0;
  for (size_t i = 0; i < N; ++i)
    for (size_t j = 0; j < N; ++j) scale = std::max(scale, std::abs(c[i][j]));
  for (size_t i = 0; i < N; ++i) {
    if (c[i][i] < 0.0) return "covariance has a negative variance";
    for (size_t j = i + 1; j < N; ++j)
      if (std::abs(c[i][j] - c[j][i]) > 1e-9 * scale) return "covariance not symmetric";
  }
  return "";
}

std::optional<std::string> validate(const features_t& m, const Limits& lim) {
  if (auto e = checkTime(m.utime, m.seq)) return e;
  if (m.num_features < 0 || m.num_features > lim.max_features)
    return "num_features " + std::to_string(m.num_features) + " outside 0.." + std::to_string(lim.max_features);
  if (auto e = countMismatch("num_features", m.num_features, m.features.size())) return e;
  if (!allFinite(m.camera_position_m)) return "non-finite camera_position_m";
  for (int i = 0; i < m.num_features; ++i) {
    const feature_t& f = m.features[static_cast<size_t>(i)];
    const std::string at = "feature " + std::to_string(i) + ": ";
    if (f.kind != feature_t::KIND_CEILING_LIGHT && f.kind != feature_t::KIND_VERTICAL_LINE)
      return at + "unknown kind " + std::to_string(f.kind);
    if (!finite(f.azimuth_rad) || !finite(f.elevation_rad) || !allFinite(f.covariance) || !finite(f.u_px) ||
        !finite(f.v_px) || !finite(f.size_px) || !finite(f.length_px) || !finite(f.strength))
      return at + "non-finite value";
    // The contract wraps azimuths to (-pi, pi]; -pi (what atan2 returns for y = -0) names the same
    // direction as pi and is accepted.
    if (std::abs(f.azimuth_rad) > M_PI + 1e-9) return at + "azimuth outside [-pi, pi]";
    if (std::abs(f.elevation_rad) > M_PI / 2 + 1e-9) return at + "elevation outside [-pi/2, pi/2]";
    if (!f.has_elevation && f.elevation_rad != 0.0) return at + "elevation given with has_elevation false";
    if (!(f.covariance[0][0] > 0.0)) return at + "azimuth variance must be > 0";
    if (f.has_elevation) {
      const double det = f.covariance[0][0] * f.covariance[1][1] - f.covariance[0][1] * f.covariance[1][0];
      if (!(f.covariance[1][1] > 0.0) || !(det > 0.0)) return at + "covariance not positive definite";
      // Symmetric up to rounding: the filter's paths would otherwise read different matrices.
      if (std::abs(f.covariance[0][1] - f.covariance[1][0]) > 1e-9 * std::sqrt(f.covariance[0][0] * f.covariance[1][1]))
        return at + "covariance not symmetric";
    }
    for (int c = 0; c < 3; ++c)
      if (!(f.colour_a[c] >= 0.0f && f.colour_a[c] <= 255.0f && f.colour_b[c] >= 0.0f && f.colour_b[c] <= 255.0f))
        return at + "colour outside 0..255";
  }
  return std::nullopt;
}

std::optional<std::string> validate(const odometry_t& m, const Limits&) {
  if (auto e = checkTime(m.utime, m.seq)) return e;
  if (!finite(m.x_m) || !finite(m.y_m) || !finite(m.theta_rad) || !finite(m.v_mps) || !finite(m.omega_radps))
    return "non-finite pose or velocity";
  return std::nullopt;
}

std::optional<std::string> validate(const pose_t& m, const Limits&) {
  if (auto e = checkTime(m.utime, m.seq)) return e;
  if (!finite(m.x_m) || !finite(m.y_m) || !finite(m.theta_rad)) return "non-finite pose";
  if (const std::string c = covarianceProblem(m.covariance); !c.empty()) return c;
  if (!finite(m.effective_sample_size) || m.effective_sample_size < 0.0)
    return "effective_sample_size must be finite and >= 0";
  if (m.num_particles < 0) return "negative num_particles";
  return std::nullopt;
}

std::optional<std::string> validate(const map_t& m, const Limits& lim) {
  if (auto e = checkTime(m.utime, m.seq)) return e;
  if (m.num_landmarks < 0 || m.num_landmarks > lim.max_landmarks) return "num_landmarks out of range";
  if (auto e = countMismatch("num_landmarks", m.num_landmarks, m.landmarks.size())) return e;
  if (m.num_candidates < 0) return "negative num_candidates " + std::to_string(m.num_candidates);
  for (int i = 0; i < m.num_landmarks; ++i) {
    const landmark_t& l = m.landmarks[static_cast<size_t>(i)];
    const std::string at = "landmark " + std::to_string(i) + ": ";
    if (!allFinite(l.position_m)) return at + "non-finite position";
    if (const std::string c = covarianceProblem(l.covariance); !c.empty()) return at + c;
    if (l.kind != feature_t::KIND_CEILING_LIGHT && l.kind != feature_t::KIND_VERTICAL_LINE)
      return at + "unknown kind " + std::to_string(l.kind);
    if (l.type < 0 || l.type > 2) return at + "type " + std::to_string(l.type) + " outside 0..2";
  }
  return std::nullopt;
}

std::optional<std::string> validate(const particles_t& m, const Limits& lim) {
  if (auto e = checkTime(m.utime, m.seq)) return e;
  if (m.num_particles < 0 || m.num_particles > lim.max_particles) return "num_particles out of range";
  for (const size_t n : {m.x_m.size(), m.y_m.size(), m.theta_rad.size(), m.weight.size()})
    if (auto e = countMismatch("num_particles", m.num_particles, n)) return e;
  for (size_t i = 0; i < static_cast<size_t>(m.num_particles); ++i) {
    if (!finite(m.x_m[i]) || !finite(m.y_m[i]) || !finite(m.theta_rad[i]) || !finite(m.weight[i]))
      return "particle " + std::to_string(i) + ": non-finite value";
    if (m.weight[i] < 0.0) return "particle " + std::to_string(i) + ": negative weight";
  }
  return std::nullopt;
}

std::optional<std::string> validate(const process_status_t& m, const Limits&) {
  if (auto e = checkTime(m.utime, m.seq)) return e;  // utime: the publisher's wall clock
  if (m.state < process_status_t::STATE_STARTING || m.state > process_status_t::STATE_ERROR)
    return "unknown state " + std::to_string(m.state);
  return std::nullopt;
}

std::optional<std::string> validate(const associations_t& m, const Limits& lim) {
  if (auto e = checkTime(m.utime, m.seq)) return e;
  if (m.num_features < 0 || m.num_features > lim.max_features) return "num_features out of range";
  if (auto e = countMismatch("num_features", m.num_features, m.landmark_id.size())) return e;
  for (size_t i = 0; i < static_cast<size_t>(m.num_features); ++i)
    if (m.landmark_id[i] < +associations_t::NOT_ASSOCIATED)
      return "feature " + std::to_string(i) + ": landmark_id " + std::to_string(m.landmark_id[i]) + " below -2";
  return std::nullopt;
}

std::optional<std::string> validate(const feature_labels_t& m, const Limits& lim) {
  if (auto e = checkTime(m.utime, m.seq)) return e;
  if (m.features_seq < 0) return "negative features_seq " + std::to_string(m.features_seq);
  if (m.num_features < 0 || m.num_features > lim.max_features) return "num_features out of range";
  if (auto e = countMismatch("num_features", m.num_features, m.landmark_id.size())) return e;
  if (auto e = countMismatch("num_features", m.num_features, m.source_code.size())) return e;
  for (size_t i = 0; i < static_cast<size_t>(m.num_features); ++i)
    if (m.landmark_id[i] < +feature_labels_t::UNKNOWN)
      return "feature " + std::to_string(i) + ": landmark_id " + std::to_string(m.landmark_id[i]) + " below -2";
  return std::nullopt;
}

std::optional<std::string> validate(const slam_health_t& m, const Limits& lim) {
  if (auto e = checkTime(m.utime, m.seq)) return e;
  if (m.state < slam_health_t::STATE_OK || m.state > slam_health_t::STATE_DIVERGED)
    return "unknown state " + std::to_string(m.state);
  if (m.num_particles < 0 || m.num_particles > lim.max_particles) return "num_particles out of range";
  const double values[] = {m.effective_sample_size,
                           m.nis,
                           m.nis_dof,
                           m.nis_window_per_dof,
                           m.nis_window_dof,
                           m.nis_lower,
                           m.nis_upper,
                           m.window_statistic,
                           m.window_travel_m,
                           m.total_statistic,
                           m.total_travel_m,
                           m.divergence_threshold};
  for (double v : values)
    if (!finite(v) || v < 0.0) return "a statistic that is negative or not finite";
  if (m.exceedances < 0) return "negative exceedances";
  return std::nullopt;
}

std::optional<std::string> validate(const slam_trajectory_t& m, const Limits&) {
  if (auto e = checkTime(m.utime, m.seq)) return e;
  if (m.num_keyframes < 0) return "negative num_keyframes";
  for (std::size_t n : {m.keyframe_utime.size(), m.x_m.size(), m.y_m.size(), m.theta_rad.size()})
    if (auto e = countMismatch("num_keyframes", m.num_keyframes, n)) return e;
  for (std::size_t k = 0; k < static_cast<std::size_t>(m.num_keyframes); ++k) {
    if (!finite(m.x_m[k]) || !finite(m.y_m[k]) || !finite(m.theta_rad[k]))
      return "keyframe " + std::to_string(k) + ": pose not finite";
    if (k > 0 && m.keyframe_utime[k] <= m.keyframe_utime[k - 1])
      return "keyframe " + std::to_string(k) + ": utime not after the one before";
  }
  if (m.num_landmarks < 0 || m.num_bearings < 0 || m.num_removed < 0 || m.iterations < 0) return "a negative count";
  if (!finite(m.final_cost) || m.final_cost < 0.0) return "final_cost negative or not finite";
  return std::nullopt;
}

std::optional<std::string> validate(const slam_localisation_t& m, const Limits&) {
  if (auto e = checkTime(m.utime, m.seq)) return e;
  if (m.state < slam_localisation_t::STATE_SEARCHING || m.state > slam_localisation_t::STATE_LOST)
    return "state " + std::to_string(m.state) + " outside 0..3";
  if (m.num_hypotheses < 0 || m.num_tracked < 0 || m.num_frames < 0 || m.num_reported < 0) return "a negative count";
  if (m.num_reported > m.num_tracked) return "num_reported above num_tracked";
  for (std::size_t n : {m.x_m.size(), m.y_m.size(), m.theta_rad.size(), m.covariance.size(),
                        m.relative_log_likelihood.size(), m.frames_explained.size(), m.travel_m.size()})
    if (auto e = countMismatch("num_reported", m.num_reported, n)) return e;
  for (std::size_t k = 0; k < static_cast<std::size_t>(m.num_reported); ++k) {
    const std::string h = "hypothesis " + std::to_string(k) + ": ";
    if (!finite(m.x_m[k]) || !finite(m.y_m[k]) || !finite(m.theta_rad[k])) return h + "pose not finite";
    if (m.covariance[k].size() != 9)
      return h + "covariance of " + std::to_string(m.covariance[k].size()) + " values, not 9";
    for (double c : m.covariance[k])
      if (!finite(c)) return h + "covariance not finite";
    if (!finite(m.relative_log_likelihood[k]) || m.relative_log_likelihood[k] > 0.0)
      return h + "relative_log_likelihood above 0 or not finite";
    if (m.frames_explained[k] < 0 || !finite(m.travel_m[k]) || m.travel_m[k] < 0.0)
      return h + "negative frames_explained or travel_m";
  }
  return std::nullopt;
}

}  // namespace omnislam::lcmio
