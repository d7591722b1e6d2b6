// Decoding of received bytes as a message of the contract, safe against lying sizes.
//
// lcm-gen's decode() resizes each array to the count the bytes declare before it checks that the
// bytes hold that many elements, and assigns each string the length they declare: a count of -1 or
// 2^31-1 throws (std::length_error, std::bad_alloc) out of the LCM callback, and a count of 20
// million allocates and zeroes 2.5 GB for a 180-byte message. decode() below first walks the
// bytes' strings and arrays and refuses any length that does not fit in what is left, then calls
// lcm-gen's decode, whose result must use every byte.
#pragma once

#include <cstddef>
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

/// The strings and arrays of the encoded body (after the 8-byte fingerprint) fit in `size` bytes:
/// nothing, or the first field that does not, e.g. "num_features -1 outside 0..10 (what 1140 bytes hold)".
/// One overload per type of the contract (the pointer only selects it).
std::optional<std::string> checkEncodedLengths(const image_t*, const uint8_t* body, size_t size);
std::optional<std::string> checkEncodedLengths(const features_t*, const uint8_t* body, size_t size);
std::optional<std::string> checkEncodedLengths(const map_t*, const uint8_t* body, size_t size);
std::optional<std::string> checkEncodedLengths(const particles_t*, const uint8_t* body, size_t size);
std::optional<std::string> checkEncodedLengths(const associations_t*, const uint8_t* body, size_t size);
std::optional<std::string> checkEncodedLengths(const feature_labels_t*, const uint8_t* body, size_t size);
std::optional<std::string> checkEncodedLengths(const process_status_t*, const uint8_t* body, size_t size);
std::optional<std::string> checkEncodedLengths(const slam_health_t*, const uint8_t* body, size_t size);
std::optional<std::string> checkEncodedLengths(const slam_trajectory_t*, const uint8_t* body, size_t size);
std::optional<std::string> checkEncodedLengths(const slam_localisation_t*, const uint8_t* body, size_t size);
inline std::optional<std::string> checkEncodedLengths(const pose_t*, const uint8_t*, size_t) { return std::nullopt; }
inline std::optional<std::string> checkEncodedLengths(const odometry_t*, const uint8_t*, size_t) {
  return std::nullopt;
}

/// Decodes `size` bytes as one Msg into `out`. Nothing on success, else a one-line reason:
/// "wrong type (fingerprint)", a length that does not fit (checkEncodedLengths), or "corrupt".
template <class Msg>
std::optional<std::string> decode(const void* data, size_t size, Msg& out) {
  const auto* bytes = static_cast<const uint8_t*>(data);
  if (size < 8) return std::string("shorter than a fingerprint");
  uint64_t hash = 0;
  for (int i = 0; i < 8; ++i) hash = (hash << 8) | bytes[i];
  if (hash != static_cast<uint64_t>(Msg::getHash())) return std::string("wrong type (fingerprint)");
  if (auto why = checkEncodedLengths(static_cast<const Msg*>(nullptr), bytes + 8, size - 8)) return why;
  if (size > 0x7fffffff) return std::string("larger than 2 GB");
  try {
    const int n = out.decode(data, 0, static_cast<int>(size));
    if (n < 0 || static_cast<size_t>(n) != size) return std::string("corrupt");
  } catch (const std::exception& e) {  // not expected after the checks above; never let it escape
    return std::string("corrupt (") + e.what() + ")";
  }
  return std::nullopt;
}

}  // namespace omnislam::lcmio
