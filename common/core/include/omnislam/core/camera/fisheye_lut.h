// The paper's look-up-table inverse of the Pajdla-Bakstein model (paper 000, sec. III-A, fig. 2):
// per pixel, the range of (azimuth, zenith) angles whose eq.-1 projection falls in that pixel.
//
// Build (once): sample phi_j = -pi + j delta_phi (j = 0 .. ceil(2 pi / delta_phi) - 1) and
// zeta_k = k delta_zeta (k = 0, 1, ..., plus zeta = max_zenith_rad itself); project each sample with
// eq. 1; the pixel hit is (round(u), round(v)); keep per pixel min and max of phi and of zeta.
// Lookup: the mid-range (min + max) / 2 of each angle (azimuth wrapped to (-pi, pi]) and the
// half-ranges as a measure of the pixel's angular extent. Angles in rad, camera frame C (see
// pajdla_bakstein.h); zeta is the zenith angle from +z_C.
//
// Choices (docs/design/camera-models.md):
//  - Azimuths are unwrapped per pixel around the pixel's running mid-range, so pixels on the -x_C
//    half-axis (phi near +-pi) get a correct range. The pixel(s) containing the optical axis see
//    every azimuth: their azimuth mid-range is meaningless, but their zenith is ~0 so the bearing
//    error stays below the pixel's size.
//  - Pixels never hit (outside the image circle, or holes left by too coarse steps) are reported as
//    invalid (lookup() returns nullopt); nothing is filled from neighbours. With the default steps
//    every pixel whose centre is more than 1 px inside the image circle is hit.
//  - Storage: 4 floats per pixel (phi_min, phi_max, zeta_min, zeta_max), row-major; a pixel that was
//    never hit has zeta_min > zeta_max. 640 x 480 -> 4 915 200 bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "omnislam/core/camera/pajdla_bakstein.h"

namespace omnislam::camera {

struct FisheyeLutOptions {
  /// Azimuth sampling step [rad]; 0.0005 rad = 0.12 px along the image circle (r = 234.7 px). In [1e-6, 0.1].
  double delta_phi_rad = 0.0005;
  /// Zenith sampling step [rad]; 0.0005 rad <= 0.08 px radially (dr/dzeta <= 153 px/rad). In [1e-6, 0.1].
  double delta_zeta_rad = 0.0005;
};

/// One pixel's entry: mid-ranges and half-ranges [rad].
struct LutBearing {
  double azimuth_rad = 0.0;            ///< (phi_min + phi_max) / 2, wrapped to (-pi, pi]
  double zenith_rad = 0.0;             ///< (zeta_min + zeta_max) / 2, angle from +z_C
  double azimuth_halfrange_rad = 0.0;  ///< (phi_max - phi_min) / 2
  double zenith_halfrange_rad = 0.0;   ///< (zeta_max - zeta_min) / 2
  /// Unit direction in C: (sin zeta cos phi, sin zeta sin phi, cos zeta).
  Eigen::Vector3d unit_C() const;
};

class FisheyeLut {
 public:
  /// Samples eq. 1 as described above. Throws std::invalid_argument for options out of range.
  static FisheyeLut build(const PajdlaBaksteinCamera& camera, const FisheyeLutOptions& options = FisheyeLutOptions{});
  /// nullopt when options are in range, else a message naming the field.
  static std::optional<std::string> validate(const FisheyeLutOptions& options);

  /// Entry of pixel (col, row); nullopt when outside the image or never hit.
  std::optional<LutBearing> lookup(int col, int row) const;
  /// Entry of the pixel containing px (nearest pixel centre); nullopt as above.
  std::optional<LutBearing> lookup(const Eigen::Vector2d& px) const;
  bool wasHit(int col, int row) const;
  std::size_t hitCount() const;

  int widthPx() const { return camera_.width_px; }
  int heightPx() const { return camera_.height_px; }
  const PajdlaBaksteinParams& cameraParams() const { return camera_; }
  const FisheyeLutOptions& options() const { return options_; }
  /// Bytes held by this object (table storage + the object itself).
  std::size_t memoryBytes() const;

  /// Versioned little-endian byte image (format in docs/design/camera-models.md): magic "OMNILUT\0",
  /// u32 version = 1, u32 width, u32 height, f64 delta_phi, f64 delta_zeta, f64 x 8 camera parameters
  /// (a, b, c, d, u0, v0, beta, max_zenith), u64 float count (= 4 width height), then the floats (f32).
  std::vector<std::uint8_t> serialize() const;
  /// Inverse of serialize(). nullopt (and *error set when given) on a wrong magic, version, size,
  /// invalid camera parameters or options, or a byte count that does not match the header.
  static std::optional<FisheyeLut> deserialize(const std::vector<std::uint8_t>& bytes, std::string* error = nullptr);

 private:
  FisheyeLut(const PajdlaBaksteinParams& camera, const FisheyeLutOptions& options);
  std::size_t index(int col, int row) const {
    return 4 *
           (static_cast<std::size_t>(row) * static_cast<std::size_t>(camera_.width_px) + static_cast<std::size_t>(col));
  }

  PajdlaBaksteinParams camera_;
  FisheyeLutOptions options_;
  std::vector<float> cells_;  ///< 4 per pixel: phi_min, phi_max, zeta_min, zeta_max
};

}  // namespace omnislam::camera
