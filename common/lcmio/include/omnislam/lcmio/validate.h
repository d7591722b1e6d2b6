// Validation of decoded messages: finite numbers, sane sizes and ranges. Each function returns a
// one-line reason when the message must be refused, or nothing when it is acceptable.
#pragma once

#include "omnislam/core/limits.h"
#include <cstdint>
#include <optional>
#include <string>

#include "omnislam/associations_t.hpp"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/image_t.hpp"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/particles_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/process_status_t.hpp"
#include "omnislam/slam_health_t.hpp"
#include "omnislam/slam_localisation_t.hpp"
#include "omnislam/slam_trajectory_t.hpp"

namespace omnislam::lcmio {

/// The largest utime accepted (omnislam/core/limits.h: 2^62 us).
inline constexpr int64_t kMaxUtime = omnislam::kMaxUtime;

/// Limits on what a process accepts (a message beyond them is refused, not truncated).
struct Limits {
  int max_image_side_px = 8192;
  int max_image_bytes = 64 * 1024 * 1024;
  int max_features = 4096;
  int max_landmarks = kMaxMapLandmarks;  ///< omnislam/core/limits.h
  int max_particles = 100000;
};

std::optional<std::string> validate(const image_t& m, const Limits& lim = {});
std::optional<std::string> validate(const features_t& m, const Limits& lim = {});
std::optional<std::string> validate(const odometry_t& m, const Limits& lim = {});
std::optional<std::string> validate(const pose_t& m, const Limits& lim = {});
std::optional<std::string> validate(const map_t& m, const Limits& lim = {});
std::optional<std::string> validate(const particles_t& m, const Limits& lim = {});
std::optional<std::string> validate(const process_status_t& m, const Limits& lim = {});
std::optional<std::string> validate(const associations_t& m, const Limits& lim = {});
std::optional<std::string> validate(const feature_labels_t& m, const Limits& lim = {});
std::optional<std::string> validate(const slam_health_t& m, const Limits& lim = {});        ///< since 0.3
std::optional<std::string> validate(const slam_trajectory_t& m, const Limits& lim = {});    ///< since 0.4
std::optional<std::string> validate(const slam_localisation_t& m, const Limits& lim = {});  ///< since 0.5

}  // namespace omnislam::lcmio
