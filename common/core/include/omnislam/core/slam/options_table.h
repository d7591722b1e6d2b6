// One table per SLAM options struct (FastSlamOptions and its motion, perception and candidate parts):
// per field its config key, C++ member, unit, accepted range, meaning; the default is the
// struct's in-class value. The core's validate(), the YAML parser (common/config), the start-up
// echo and the key table of docs/slam-process.md are all produced from these tables, so they
// cannot drift. Plain descriptors: Eigen and the standard library only.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "omnislam/core/angles.h"
#include "omnislam/core/slam/fastslam.h"
#include "omnislam/core/slam/health_monitor.h"

namespace omnislam::slam::options {

/// Which ends of [lo, hi] belong to the range (the same three forms as config::Node::Open).
enum class Bounds : std::uint8_t {
  kClosed,    ///< [lo, hi]
  kLowOpen,   ///< (lo, hi]
  kHighOpen,  ///< [lo, hi)
};

enum class Kind : std::uint8_t { kReal, kInt, kBool, kVec3, kEnum };

/// One field of the options struct S as a config file writes it. The range and the key's value
/// are in the key's unit; with `degrees` the key is in degrees and the member in radians
/// (deg2rad / rad2deg of angles.h).
template <class S>
struct Field {
  const char* key = "";    ///< key inside the struct's section, its unit in the suffix (_deg, _m)
  const char* field = "";  ///< the C++ member
  const char* unit = "";   ///< unit of the key's value ("" = none)
  Kind kind = Kind::kReal;
  double lo = 0.0, hi = 0.0;  ///< accepted range of the key's value (kReal, kInt, each kVec3 component)
  Bounds bounds = Bounds::kClosed;
  bool degrees = false;
  const char* doc = "";  ///< one line: what it means
  double S::*real = nullptr;
  int S::*integer = nullptr;
  bool S::*flag = nullptr;
  Eigen::Vector3d S::*vec3 = nullptr;
  // kEnum: the names in the order of the enum's values, and the member read and written as an index.
  const std::vector<std::string>* names = nullptr;
  int (*get_index)(const S&) = nullptr;
  void (*set_index)(S&, int) = nullptr;

  /// The member's value in the key's unit (kReal, kInt, kBool as 0/1, kEnum as the index).
  double value(const S& s) const {
    switch (kind) {
      case Kind::kReal: return degrees ? rad2deg(s.*real) : s.*real;
      case Kind::kInt: return static_cast<double>(s.*integer);
      case Kind::kBool: return s.*flag ? 1.0 : 0.0;
      case Kind::kEnum: return static_cast<double>(get_index(s));
      case Kind::kVec3: break;
    }
    return 0.0;
  }
  /// The range's ends in the member's units (radians for a key in degrees).
  double memberLo() const { return degrees ? deg2rad(lo) : lo; }
  double memberHi() const { return degrees ? deg2rad(hi) : hi; }
  /// v (in the member's units) inside the range; false for NaN.
  bool memberInRange(double v) const {
    const bool low_ok = bounds == Bounds::kLowOpen ? v > memberLo() : v >= memberLo();
    const bool high_ok = bounds == Bounds::kHighOpen ? v < memberHi() : v <= memberHi();
    return low_ok && high_ok;
  }
};

constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// The table of each struct, in the order the docs and the echo list them.
const std::vector<Field<FastSlamOptions>>& fastSlamFields();      ///< keys `filter.*` (not the parts below)
const std::vector<Field<MotionNoiseOptions>>& motionFields();     ///< keys `filter.motion.*`
const std::vector<Field<PerceptionOptions>>& perceptionFields();  ///< keys `filter.perception.*`
const std::vector<Field<CandidateOptions>>& candidateFields();    ///< keys `filter.candidates.*`
const std::vector<Field<KeyframeOptions>>& keyframeFields();      ///< keys `filter.keyframes.*`
const std::vector<Field<HealthOptions>>& healthFields();          ///< keys `health.*` (health_monitor.h)

/// Names of the enum fields (index = the enum's value).
const std::vector<std::string>& associationNames();   ///< "hungarian", "ml"
const std::vector<std::string>& proposalNames();      ///< "fastslam2", "fastslam1"
const std::vector<std::string>& motionModelNames();   ///< "chord", "translate_then_rotate"
const std::vector<std::string>& weightTermNames();    ///< "density", "consistency"
const std::vector<std::string>& healthPolicyNames();  ///< "report", "fallback_odometry"

/// The first field of s outside its range, as "field must be in [lo, hi], got v" in the member's
/// own units (radians for a _deg key); empty when every field is in range.
template <class S>
std::string checkRanges(const S& s, const std::vector<Field<S>>& table);

/// "key=value" of every field of s, space-separated, in the key's units (the start-up echo).
template <class S>
std::string describeFields(const S& s, const std::vector<Field<S>>& table);

/// The range of f as text: "[lo, hi]", "(0, 1]"...; "inf" for an infinite end; "-" for bool, the
/// names for an enum.
template <class S>
std::string rangeText(const Field<S>& f);
/// The value of f in s as text (a bool true/false, an enum its name, a vector [x, y, z]).
template <class S>
std::string valueText(const Field<S>& f, const S& s);

}  // namespace omnislam::slam::options
