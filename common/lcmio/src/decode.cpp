// Length checks of encoded messages before lcm-gen's decode: see decode.h. The walks follow the
// field order of the frozen .lcm files (a new version of a type is a new type with its own walk).
#include "omnislam/lcmio/decode.h"

#include <cstring>

namespace omnislam::lcmio {
namespace {

/// Walks big-endian LCM fields; the first field that does not fit is kept as `error`.
class Walk {
 public:
  Walk(const uint8_t* p, size_t n) : p_(p), n_(n) {}

  /// Fixed-size fields: `bytes` of them.
  Walk& skip(size_t bytes) {
    if (!error && bytes > n_ - pos_) error = "truncated";
    if (!error) pos_ += bytes;
    return *this;
  }
  /// An int32 field, e.g. an array count; 0 after an error.
  int32_t i32() {
    if (!error && 4 > n_ - pos_) error = "truncated";
    if (error) return 0;
    const uint32_t v = (uint32_t{p_[pos_]} << 24) | (uint32_t{p_[pos_ + 1]} << 16) | (uint32_t{p_[pos_ + 2]} << 8) |
                       uint32_t{p_[pos_ + 3]};
    pos_ += 4;
    return static_cast<int32_t>(v);
  }
  /// A string: int32 length counting its NUL, then the bytes, the last of them the only NUL
  /// (lcm-gen's decode does not check it, and its encode would then write another length).
  Walk& str(const char* field) {
    const int32_t len = i32();
    if (!error && (len < 1 || static_cast<size_t>(len) > n_ - pos_))
      error = std::string(field) + " length " + std::to_string(len) + " outside 1.." + std::to_string(n_ - pos_);
    if (!error && (p_[pos_ + static_cast<size_t>(len) - 1] != 0 ||
                   std::memchr(p_ + pos_, 0, static_cast<size_t>(len) - 1) != nullptr))
      error = std::string(field) + " is not one NUL-terminated string";
    return skip(error ? 0 : static_cast<size_t>(len));
  }
  /// `count` elements of `elem_bytes` each (count read before with i32()).
  Walk& array(const char* count_field, int32_t count, size_t elem_bytes) {
    const size_t fits = (n_ - pos_) / elem_bytes;
    if (!error && (count < 0 || static_cast<size_t>(count) > fits))
      error = std::string(count_field) + " " + std::to_string(count) + " outside 0.." + std::to_string(fits) +
              " (what the " + std::to_string(n_ - pos_) + " bytes left hold)";
    return skip(error ? 0 : static_cast<size_t>(count) * elem_bytes);
  }

  std::optional<std::string> error;

 private:
  const uint8_t* p_;
  size_t n_;
  size_t pos_ = 0;
};

// Encoded sizes of the fixed-size element types (sum of their fields' sizes, no padding).
constexpr size_t kFeatureBytes = 1 + 8 + 8 + 1 + 4 * 8 + 2 * 8 + 3 * 8 + 2 * 3 * 4;  // feature_t: 114
constexpr size_t kLandmarkBytes = 8 + 3 * 8 + 9 * 8 + 1 + 4 + 1;                     // landmark_t: 110

/// utime, seq and another int64, then an int32 count of elements of `elem_bytes` (the arrays of
/// map_t, particles_t, associations_t and feature_labels_t; what follows is fixed-size).
std::optional<std::string> countAfterThreeInt64s(const uint8_t* body, size_t size, const char* count_field,
                                                 size_t elem_bytes) {
  Walk w(body, size);
  w.skip(3 * 8);
  const int32_t n = w.i32();
  w.array(count_field, n, elem_bytes);
  return w.error;
}

}  // namespace

std::optional<std::string> checkEncodedLengths(const image_t*, const uint8_t* body, size_t size) {
  Walk w(body, size);
  w.skip(8 + 8).str("camera_name").skip(4 + 4 + 4 + 1);
  const int32_t n = w.i32();
  w.array("size", n, 1);
  return w.error;
}

std::optional<std::string> checkEncodedLengths(const features_t*, const uint8_t* body, size_t size) {
  Walk w(body, size);
  w.skip(8 + 8 + 8).str("detector").skip(3 * 8);
  const int32_t n = w.i32();
  w.array("num_features", n, kFeatureBytes);
  return w.error;
}

std::optional<std::string> checkEncodedLengths(const map_t*, const uint8_t* body, size_t size) {
  return countAfterThreeInt64s(body, size, "num_landmarks", kLandmarkBytes);
}

std::optional<std::string> checkEncodedLengths(const particles_t*, const uint8_t* body, size_t size) {
  return countAfterThreeInt64s(body, size, "num_particles", 4 * 8);  // x_m, y_m, theta_rad, weight
}

std::optional<std::string> checkEncodedLengths(const associations_t*, const uint8_t* body, size_t size) {
  return countAfterThreeInt64s(body, size, "num_features", 8);  // landmark_id
}

std::optional<std::string> checkEncodedLengths(const feature_labels_t*, const uint8_t* body, size_t size) {
  return countAfterThreeInt64s(body, size, "num_features", 8 + 4);  // landmark_id, source_code
}

std::optional<std::string> checkEncodedLengths(const process_status_t*, const uint8_t* body, size_t size) {
  Walk w(body, size);
  w.skip(8 + 8).str("name").skip(4 + 1 + 5 * 8).str("last_error").str("detail");
  return w.error;
}

std::optional<std::string> checkEncodedLengths(const slam_health_t*, const uint8_t* body, size_t size) {
  Walk w(body, size);
  // utime, seq, input_seq, state; reason; fallback, num_particles, effective_sample_size, resampled,
  // the 6 NIS and 4 departure doubles, divergence_threshold, exceedances.
  w.skip(3 * 8 + 1).str("reason").skip(1 + 4 + 8 + 1 + 6 * 8 + 4 * 8 + 8 + 4);
  return w.error;
}

std::optional<std::string> checkEncodedLengths(const slam_trajectory_t*, const uint8_t* body, size_t size) {
  Walk w(body, size);
  w.skip(4 * 8 + 1).str("failure").skip(4 * 4 + 8 + 1);
  const int32_t n = w.i32();
  w.array("num_keyframes", n, 4 * 8);  // keyframe_utime, x_m, y_m, theta_rad: four arrays of n
  return w.error;
}

std::optional<std::string> checkEncodedLengths(const slam_localisation_t*, const uint8_t* body, size_t size) {
  Walk w(body, size);
  w.skip(3 * 8 + 1 + 3 * 4);
  const int32_t n = w.i32();
  // x_m, y_m, theta_rad, covariance[9], relative_log_likelihood, frames_explained (int32), travel_m
  w.array("num_reported", n, 3 * 8 + 9 * 8 + 8 + 4 + 8);
  return w.error;
}

}  // namespace omnislam::lcmio
