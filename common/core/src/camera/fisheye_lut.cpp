// Look-up-table inverse of the Pajdla-Bakstein model (paper 000, sec. III-A): build, lookup and a
// versioned byte image (no file I/O here; a tool writes the bytes).
#include "omnislam/core/camera/fisheye_lut.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace omnislam::camera {

namespace {

constexpr char kMagic[8] = {'O', 'M', 'N', 'I', 'L', 'U', 'T', '\0'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 4 + 8 + 8 + 8 * 8 + 8;  // 108
constexpr float kEmptyMin = std::numeric_limits<float>::infinity();

void putU(std::vector<std::uint8_t>& out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<std::uint8_t>((v >> (8 * i)) & 0xFFu));
}
void putF64(std::vector<std::uint8_t>& out, double x) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &x, sizeof bits);
  putU(out, bits, 8);
}

// Little-endian reader over a byte vector; every read is bounds-checked by the caller's size check.
struct Reader {
  const std::vector<std::uint8_t>& b;
  std::size_t at = 0;
  std::uint64_t u(int bytes) {
    std::uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= static_cast<std::uint64_t>(b[at + i]) << (8 * i);
    at += bytes;
    return v;
  }
  double f64() {
    const std::uint64_t bits = u(8);
    double x = 0.0;
    std::memcpy(&x, &bits, sizeof x);
    return x;
  }
  float f32() {
    const auto bits = static_cast<std::uint32_t>(u(4));
    float x = 0.0f;
    std::memcpy(&x, &bits, sizeof x);
    return x;
  }
};

}  // namespace

Eigen::Vector3d LutBearing::unit_C() const {
  const double s = std::sin(zenith_rad);
  return {s * std::cos(azimuth_rad), s * std::sin(azimuth_rad), std::cos(zenith_rad)};
}

std::optional<std::string> FisheyeLut::validate(const FisheyeLutOptions& o) {
  if (!(o.delta_phi_rad >= 1e-6 && o.delta_phi_rad <= 0.1)) return std::string("delta_phi_rad must be in [1e-6, 0.1]");
  if (!(o.delta_zeta_rad >= 1e-6 && o.delta_zeta_rad <= 0.1))
    return std::string("delta_zeta_rad must be in [1e-6, 0.1]");
  return std::nullopt;
}

FisheyeLut::FisheyeLut(const PajdlaBaksteinParams& camera, const FisheyeLutOptions& options)
    : camera_(camera), options_(options) {
  cells_.resize(4 * static_cast<std::size_t>(camera_.width_px) * static_cast<std::size_t>(camera_.height_px));
  for (std::size_t i = 0; i < cells_.size(); i += 4) {
    cells_[i + 0] = kEmptyMin;
    cells_[i + 1] = -kEmptyMin;
    cells_[i + 2] = kEmptyMin;
    cells_[i + 3] = -kEmptyMin;
  }
}

FisheyeLut FisheyeLut::build(const PajdlaBaksteinCamera& camera, const FisheyeLutOptions& options) {
  if (const auto err = validate(options)) throw std::invalid_argument("FisheyeLutOptions: " + *err);
  const PajdlaBaksteinParams& p = camera.params();
  FisheyeLut lut(p, options);

  const auto n_phi = static_cast<std::size_t>(std::ceil(2.0 * kPi / options.delta_phi_rad));
  std::vector<double> phi(n_phi), cos_phi(n_phi), sin_phi(n_phi);
  for (std::size_t j = 0; j < n_phi; ++j) {
    phi[j] = -kPi + static_cast<double>(j) * options.delta_phi_rad;
    cos_phi[j] = std::cos(phi[j]);
    sin_phi[j] = std::sin(phi[j]);
  }
  const auto n_zeta = static_cast<std::size_t>(std::floor(p.max_zenith_rad / options.delta_zeta_rad)) + 1;
  const bool add_edge = static_cast<double>(n_zeta - 1) * options.delta_zeta_rad < p.max_zenith_rad;

  for (std::size_t k = 0; k < n_zeta + (add_edge ? 1 : 0); ++k) {
    const double zeta = std::min(static_cast<double>(k) * options.delta_zeta_rad, p.max_zenith_rad);
    const double r = camera.radiusPx(zeta);
    const auto zf = static_cast<float>(zeta);
    for (std::size_t j = 0; j < n_phi; ++j) {
      const double u = p.u0_px + r * cos_phi[j];
      const double v = p.v0_px + p.beta * r * sin_phi[j];
      const double col = std::floor(u + 0.5), row = std::floor(v + 0.5);
      if (col < 0.0 || row < 0.0 || col >= p.width_px || row >= p.height_px) continue;
      float* cell = &lut.cells_[lut.index(static_cast<int>(col), static_cast<int>(row))];
      if (cell[2] > cell[3]) {  // first sample in this pixel
        cell[0] = cell[1] = static_cast<float>(phi[j]);
        cell[2] = cell[3] = zf;
        continue;
      }
      // Unwrap around the running mid-range so that a pixel straddling phi = +-pi keeps a short range.
      const double ref = 0.5 * (static_cast<double>(cell[0]) + static_cast<double>(cell[1]));
      double ph = phi[j];
      if (ph - ref > kPi) ph -= 2.0 * kPi;
      if (ph - ref < -kPi) ph += 2.0 * kPi;
      cell[0] = std::min(cell[0], static_cast<float>(ph));
      cell[1] = std::max(cell[1], static_cast<float>(ph));
      cell[2] = std::min(cell[2], zf);
      cell[3] = std::max(cell[3], zf);
    }
  }
  return lut;
}

bool FisheyeLut::wasHit(int col, int row) const {
  if (col < 0 || row < 0 || col >= camera_.width_px || row >= camera_.height_px) return false;
  const std::size_t i = index(col, row);
  return cells_[i + 2] <= cells_[i + 3];
}

std::size_t FisheyeLut::hitCount() const {
  std::size_t n = 0;
  for (std::size_t i = 0; i < cells_.size(); i += 4) n += cells_[i + 2] <= cells_[i + 3] ? 1 : 0;
  return n;
}

std::optional<LutBearing> FisheyeLut::lookup(int col, int row) const {
  if (!wasHit(col, row)) return std::nullopt;
  const std::size_t i = index(col, row);
  const double phi_min = cells_[i], phi_max = cells_[i + 1], zeta_min = cells_[i + 2], zeta_max = cells_[i + 3];
  LutBearing b;
  b.azimuth_rad = wrapAngle(0.5 * (phi_min + phi_max));
  b.zenith_rad = 0.5 * (zeta_min + zeta_max);
  b.azimuth_halfrange_rad = 0.5 * (phi_max - phi_min);
  b.zenith_halfrange_rad = 0.5 * (zeta_max - zeta_min);
  return b;
}

std::optional<LutBearing> FisheyeLut::lookup(const Eigen::Vector2d& px) const {
  const double col = std::floor(px.x() + 0.5), row = std::floor(px.y() + 0.5);
  if (!(col >= 0.0 && row >= 0.0 && col < camera_.width_px && row < camera_.height_px)) return std::nullopt;
  return lookup(static_cast<int>(col), static_cast<int>(row));
}

std::size_t FisheyeLut::memoryBytes() const { return sizeof(*this) + cells_.capacity() * sizeof(float); }

std::vector<std::uint8_t> FisheyeLut::serialize() const {
  std::vector<std::uint8_t> out;
  out.reserve(kHeaderBytes + cells_.size() * 4);
  for (const char ch : kMagic) out.push_back(static_cast<std::uint8_t>(ch));
  putU(out, kVersion, 4);
  putU(out, static_cast<std::uint32_t>(camera_.width_px), 4);
  putU(out, static_cast<std::uint32_t>(camera_.height_px), 4);
  putF64(out, options_.delta_phi_rad);
  putF64(out, options_.delta_zeta_rad);
  for (const double x : {camera_.a_px, camera_.b, camera_.c_px, camera_.d, camera_.u0_px, camera_.v0_px, camera_.beta,
                         camera_.max_zenith_rad}) {
    putF64(out, x);
  }
  putU(out, cells_.size(), 8);
  for (const float f : cells_) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &f, sizeof bits);
    putU(out, bits, 4);
  }
  return out;
}

std::optional<FisheyeLut> FisheyeLut::deserialize(const std::vector<std::uint8_t>& bytes, std::string* error) {
  const auto fail = [error](const std::string& msg) -> std::optional<FisheyeLut> {
    if (error) *error = "FisheyeLut::deserialize: " + msg;
    return std::nullopt;
  };
  if (bytes.size() < kHeaderBytes) {
    return fail("truncated header: " + std::to_string(bytes.size()) + " bytes < " + std::to_string(kHeaderBytes));
  }
  if (std::memcmp(bytes.data(), kMagic, 8) != 0) return fail("bad magic (not an OMNILUT byte image)");
  Reader rd{bytes, 8};
  const std::uint64_t version = rd.u(4);
  if (version != kVersion) {
    return fail("unsupported version " + std::to_string(version) + " (expected " + std::to_string(kVersion) + ")");
  }
  const std::uint64_t w = rd.u(4), h = rd.u(4);
  if (w == 0 || h == 0 || w > 32768 || h > 32768) {
    return fail("image size " + std::to_string(w) + " x " + std::to_string(h) + " out of range [1, 32768]");
  }
  FisheyeLutOptions o;
  o.delta_phi_rad = rd.f64();
  o.delta_zeta_rad = rd.f64();
  if (const auto err = validate(o)) return fail("options: " + *err);
  PajdlaBaksteinParams p;
  p.width_px = static_cast<int>(w);
  p.height_px = static_cast<int>(h);
  for (double* x : {&p.a_px, &p.b, &p.c_px, &p.d, &p.u0_px, &p.v0_px, &p.beta, &p.max_zenith_rad}) *x = rd.f64();
  if (const auto err = PajdlaBaksteinCamera::validate(p)) return fail("camera: " + *err);
  const std::uint64_t count = rd.u(8);
  if (count != 4 * w * h) {
    return fail("cell count " + std::to_string(count) + " != 4 * width * height = " + std::to_string(4 * w * h));
  }
  if (bytes.size() != kHeaderBytes + 4 * count) {
    return fail("size " + std::to_string(bytes.size()) +
                " bytes != header + 4 * count = " + std::to_string(kHeaderBytes + 4 * count));
  }
  FisheyeLut lut(p, o);
  for (float& f : lut.cells_) f = rd.f32();
  for (std::size_t i = 0; i < lut.cells_.size(); ++i)
    if (std::isnan(lut.cells_[i])) return fail("cell value " + std::to_string(i) + " is NaN");  // +-inf: empty
  return lut;
}

}  // namespace omnislam::camera
