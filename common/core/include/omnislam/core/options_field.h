// Options tables: an options struct described field by field (config key, C++ member, unit, accepted
// range, one-line meaning; the default is the struct's in-class value), and what is produced from a
// table: validate()'s range check, the start-up echo and the text of the docs table. The YAML parser
// that reads a table is in common/config (slam_config.cpp). Plain descriptors: Eigen and std only.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "omnislam/core/angles.h"

namespace omnislam::options {

/// Which ends of [lo, hi] belong to the range (the same three forms as config::Node::Open).
enum class Bounds : std::uint8_t {
  kClosed,    ///< [lo, hi]
  kLowOpen,   ///< (lo, hi]
  kHighOpen,  ///< [lo, hi)
};

/// What a key holds. kSeconds: a duration, the key in seconds, the member in whole microseconds
/// (std::int64_t, the key's value rounded to the nearest microsecond). kPath: a file path, relative
/// ones resolved against the config file's folder ("" = none).
enum class Kind : std::uint8_t { kReal, kInt, kBool, kVec3, kEnum, kSeconds, kUint64, kPath };

constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// One field of the options struct S as a config file writes it. The range and the key's value
/// are in the key's unit; with `degrees` the key is in degrees and the member in radians
/// (deg2rad / rad2deg of angles.h).
template <class S>
struct Field {
  const char* key = "";    ///< key inside the struct's section, its unit in the suffix (_deg, _m, _s)
  const char* field = "";  ///< the C++ member
  const char* unit = "";   ///< unit of the key's value ("" = none)
  Kind kind = Kind::kReal;
  double lo = 0.0, hi = 0.0;  ///< accepted range of the key's value (not kBool, kEnum, kPath)
  Bounds bounds = Bounds::kClosed;
  bool degrees = false;
  const char* doc = "";  ///< one line: what it means
  double S::*real = nullptr;
  int S::*integer = nullptr;
  bool S::*flag = nullptr;
  Eigen::Vector3d S::*vec3 = nullptr;
  std::int64_t S::*micros = nullptr;  ///< kSeconds
  std::uint64_t S::*u64 = nullptr;    ///< kUint64
  std::string S::*text = nullptr;     ///< kPath
  // kReal of a member inside a member (start_pose_W.x_m): read and written through these when
  // `real` is null.
  double (*get_real)(const S&) = nullptr;
  void (*set_real)(S&, double) = nullptr;
  // kBool of a choice held as a type (a variant's alternative) when `flag` is null: read through
  // get_flag; set_flag returns null, or why the value cannot be held with the struct's other fields
  // (e.g. a FastSLAM 2.0 choice while the proposal is FastSLAM 1.0), which the parser reports.
  bool (*get_flag)(const S&) = nullptr;
  const char* (*set_flag)(S&, bool) = nullptr;
  // kEnum: the names in the order of the enum's values, and the member read and written as an index.
  const std::vector<std::string>* names = nullptr;
  int (*get_index)(const S&) = nullptr;
  void (*set_index)(S&, int) = nullptr;

  /// kReal: the member (radians for a key in degrees).
  double realMember(const S& s) const { return real ? s.*real : get_real(s); }
  void setRealMember(S& s, double v) const {
    if (real) s.*real = v;
    else set_real(s, v);
  }
  /// kBool: the member.
  bool flagMember(const S& s) const { return flag ? s.*flag : get_flag(s); }
  /// kBool: sets the member; null, or why the value cannot be held (the member is then unchanged).
  const char* setFlagMember(S& s, bool v) const {
    if (!flag) return set_flag(s, v);
    s.*flag = v;
    return nullptr;
  }
  /// The member's value in the key's unit (kBool as 0/1, kEnum as the index; 0 for kVec3, kPath).
  double value(const S& s) const {
    switch (kind) {
      case Kind::kReal: return degrees ? rad2deg(realMember(s)) : realMember(s);
      case Kind::kInt: return static_cast<double>(s.*integer);
      case Kind::kBool: return flagMember(s) ? 1.0 : 0.0;
      case Kind::kEnum: return static_cast<double>(get_index(s));
      case Kind::kSeconds: return static_cast<double>(s.*micros) * 1e-6;
      case Kind::kUint64: return static_cast<double>(s.*u64);
      case Kind::kVec3:
      case Kind::kPath: break;
    }
    return 0.0;
  }
  /// The member's value in its own units (radians, microseconds), as the range check compares it.
  double memberValue(const S& s) const {
    if (kind == Kind::kReal) return realMember(s);
    if (kind == Kind::kSeconds) return static_cast<double>(s.*micros);
    return value(s);
  }
  /// The range's ends in the member's units (radians for a key in degrees, whole microseconds for
  /// a duration).
  double memberLo() const { return toMember(lo); }
  double memberHi() const { return toMember(hi); }
  /// v (in the member's units) inside the range; false for NaN.
  bool memberInRange(double v) const {
    const bool low_ok = bounds == Bounds::kLowOpen ? v > memberLo() : v >= memberLo();
    const bool high_ok = bounds == Bounds::kHighOpen ? v < memberHi() : v <= memberHi();
    return low_ok && high_ok;
  }

 private:
  double toMember(double key_value) const {
    if (kind == Kind::kSeconds) return std::round(key_value * 1e6);
    return degrees ? deg2rad(key_value) : key_value;
  }
};

// ---- Rows of a table, one builder per kind ----------------------------------------------------

template <class S>
Field<S> real(const char* key, double S::*m, const char* field, const char* unit, double lo, double hi, Bounds b,
              const char* doc, bool degrees = false) {
  Field<S> f;
  f.key = key, f.field = field, f.unit = unit, f.kind = Kind::kReal, f.lo = lo, f.hi = hi, f.bounds = b;
  f.degrees = degrees, f.doc = doc, f.real = m;
  return f;
}
/// kReal of a member inside a member, read and written through get / set (in the member's units).
template <class S>
Field<S> realVia(const char* key, double (*get)(const S&), void (*set)(S&, double), const char* field, const char* unit,
                 double lo, double hi, Bounds b, const char* doc, bool degrees = false) {
  Field<S> f;
  f.key = key, f.field = field, f.unit = unit, f.kind = Kind::kReal, f.lo = lo, f.hi = hi, f.bounds = b;
  f.degrees = degrees, f.doc = doc, f.get_real = get, f.set_real = set;
  return f;
}
template <class S>
Field<S> integer(const char* key, int S::*m, const char* field, double lo, double hi, const char* doc) {
  Field<S> f;
  f.key = key, f.field = field, f.kind = Kind::kInt, f.lo = lo, f.hi = hi, f.doc = doc, f.integer = m;
  return f;
}
template <class S>
Field<S> uint64(const char* key, std::uint64_t S::*m, const char* field, double lo, double hi, const char* doc) {
  Field<S> f;
  f.key = key, f.field = field, f.kind = Kind::kUint64, f.lo = lo, f.hi = hi, f.doc = doc, f.u64 = m;
  return f;
}
template <class S>
Field<S> flag(const char* key, bool S::*m, const char* field, const char* doc) {
  Field<S> f;
  f.key = key, f.field = field, f.kind = Kind::kBool, f.doc = doc, f.flag = m;
  return f;
}
/// kBool of a choice held as a type, read through get and set through set (Field::set_flag).
template <class S>
Field<S> flagVia(const char* key, bool (*get)(const S&), const char* (*set)(S&, bool), const char* field,
                 const char* doc) {
  Field<S> f;
  f.key = key, f.field = field, f.kind = Kind::kBool, f.doc = doc, f.get_flag = get, f.set_flag = set;
  return f;
}
template <class S>
Field<S> vec3(const char* key, Eigen::Vector3d S::*m, const char* field, const char* unit, double lo, double hi,
              const char* doc) {
  Field<S> f;
  f.key = key, f.field = field, f.unit = unit, f.kind = Kind::kVec3, f.lo = lo, f.hi = hi, f.doc = doc, f.vec3 = m;
  return f;
}
template <class S>
Field<S> enumeration(const char* key, const char* field, const std::vector<std::string>& names, int (*get)(const S&),
                     void (*set)(S&, int), const char* doc) {
  Field<S> f;
  f.key = key, f.field = field, f.kind = Kind::kEnum, f.doc = doc, f.names = &names, f.get_index = get;
  f.set_index = set;
  return f;
}
/// A duration: the key in seconds within [lo, hi], the member in microseconds.
template <class S>
Field<S> seconds(const char* key, std::int64_t S::*m, const char* field, double lo, double hi, const char* doc) {
  Field<S> f;
  f.key = key, f.field = field, f.unit = "s", f.kind = Kind::kSeconds, f.lo = lo, f.hi = hi, f.doc = doc;
  f.micros = m;
  return f;
}
template <class S>
Field<S> path(const char* key, std::string S::*m, const char* field, const char* doc) {
  Field<S> f;
  f.key = key, f.field = field, f.kind = Kind::kPath, f.doc = doc, f.text = m;
  return f;
}

// ---- What a table produces ---------------------------------------------------------------------

/// v as the echo and the docs print a real: 6 significant digits, "inf" / "-inf".
std::string numberText(double v);
/// A whole number exactly ("9223372036854775807" for 2^63 and beyond).
std::string integerText(double v);
/// Microseconds as seconds, exactly: 2500000 -> "2.5", 1 -> "0.000001".
std::string secondsText(std::int64_t us);

/// The range of f as text: "[lo, hi]", "(0, 1]"...; "inf" for an infinite end; "true, false" for a
/// bool, the names for an enum, "path" for a path.
template <class S>
std::string rangeText(const Field<S>& f) {
  if (f.kind == Kind::kBool) return "true, false";
  if (f.kind == Kind::kPath) return "path";
  if (f.kind == Kind::kEnum) {
    std::string s;
    for (const auto& n : *f.names) s += (s.empty() ? "" : ", ") + n;
    return s;
  }
  const bool whole = f.kind == Kind::kInt || f.kind == Kind::kUint64;
  return std::string(f.bounds == Bounds::kLowOpen ? "(" : "[") + (whole ? integerText(f.lo) : numberText(f.lo)) + ", " +
         (whole ? integerText(f.hi) : numberText(f.hi)) + (f.bounds == Bounds::kHighOpen ? ")" : "]");
}

/// The value of f in s as text, in the key's unit (a bool true/false, an enum its name, a vector
/// [x, y, z], a path as written or "" for none, whole numbers and durations exactly).
template <class S>
std::string valueText(const Field<S>& f, const S& s) {
  switch (f.kind) {
    case Kind::kBool: return f.flagMember(s) ? "true" : "false";
    case Kind::kEnum: return f.names->at(static_cast<std::size_t>(f.get_index(s)));
    case Kind::kVec3: {
      const Eigen::Vector3d& v = s.*f.vec3;
      return "[" + numberText(v.x()) + ", " + numberText(v.y()) + ", " + numberText(v.z()) + "]";
    }
    case Kind::kInt: return std::to_string(s.*f.integer);
    case Kind::kUint64: return std::to_string(s.*f.u64);
    case Kind::kSeconds: return secondsText(s.*f.micros);
    case Kind::kPath: return (s.*f.text).empty() ? "\"\"" : s.*f.text;
    case Kind::kReal: break;
  }
  return numberText(f.value(s));
}

/// The first field of s outside its range, as "field must be in [lo, hi], got v" in the member's
/// own units (radians for a _deg key, microseconds for a duration); empty when every field is in
/// range.
template <class S>
std::string checkRanges(const S& s, const std::vector<Field<S>>& table) {
  const auto fail = [](const Field<S>& f, const std::string& field, double v) {  // v in the member's units
    return field + " must be in " + std::string(f.bounds == Bounds::kLowOpen ? "(" : "[") + numberText(f.memberLo()) +
           ", " + numberText(f.memberHi()) + (f.bounds == Bounds::kHighOpen ? ")" : "]") + ", got " + numberText(v);
  };
  for (const auto& f : table) {
    if (f.kind == Kind::kVec3) {
      const Eigen::Vector3d& v = s.*f.vec3;
      for (int i = 0; i < 3; ++i) {
        if (!f.memberInRange(v(i))) return fail(f, std::string(f.field) + "." + "xyz"[i], v(i));
      }
      continue;
    }
    if (f.kind == Kind::kEnum) {
      const int i = f.get_index(s);
      if (i < 0 || i >= static_cast<int>(f.names->size())) return std::string(f.field) + " is not a known value";
      continue;
    }
    if (f.kind == Kind::kBool || f.kind == Kind::kPath) continue;
    const double v = f.memberValue(s);
    if (!f.memberInRange(v)) return fail(f, f.field, v);
  }
  return "";
}

/// "key=value" of every field of s, space-separated, in the key's units (the start-up echo).
template <class S>
std::string describeFields(const S& s, const std::vector<Field<S>>& table) {
  std::string out;
  for (const auto& f : table) out += (out.empty() ? "" : " ") + std::string(f.key) + "=" + valueText(f, s);
  return out;
}

}  // namespace omnislam::options
