// Reading an options table (omnislam/core/options_field.h) from a config section, and the rows of
// its docs table: one table per options struct drives the parser, validate()'s range check, the
// start-up echo and the generated docs (the SLAM's, the detectors', the world camera's).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <sstream>
#include <string>
#include <vector>

#include "omnislam/config/yaml_node.h"
#include "omnislam/core/angles.h"
#include "omnislam/core/options_field.h"

namespace omnislam::config {

inline Node::Open openOf(options::Bounds b) {
  return b == options::Bounds::kLowOpen    ? Node::Open::kLow
         : b == options::Bounds::kHighOpen ? Node::Open::kHigh
                                           : Node::Open::kNone;
}

/// A range end as Node::getInt takes it (2^63 and beyond: INT64_MAX).
inline int64_t wholeEnd(double v) {
  constexpr double kTwo63 = 9223372036854775808.0;
  if (v >= kTwo63) return INT64_MAX;
  if (v <= -kTwo63) return INT64_MIN;
  return static_cast<int64_t>(v);
}

/// One key of a table from section n, read within its range and converted to the member's units
/// (radians for a _deg key, microseconds for a duration in seconds); a missing key is an error.
template <class S>
void parseField(const Node& n, S& s, const options::Field<S>& f) {
  using options::Kind;
  switch (f.kind) {
    case Kind::kReal: {
      const double v = n.getDouble(f.key, f.lo, f.hi, openOf(f.bounds));
      f.setRealMember(s, f.degrees ? deg2rad(v) : v);
      break;
    }
    case Kind::kInt: s.*f.integer = static_cast<int>(n.getInt(f.key, wholeEnd(f.lo), wholeEnd(f.hi))); break;
    case Kind::kUint64: s.*f.u64 = static_cast<std::uint64_t>(n.getInt(f.key, wholeEnd(f.lo), wholeEnd(f.hi))); break;
    case Kind::kSeconds:
      s.*f.micros = static_cast<int64_t>(std::llround(n.getDouble(f.key, f.lo, f.hi, openOf(f.bounds)) * 1e6));
      break;
    case Kind::kBool:  // a choice held as a type may refuse a value the other keys exclude
      if (const char* why = f.setFlagMember(s, n.getBool(f.key))) throw ConfigError(n.where(f.key) + " " + why);
      break;
    case Kind::kVec3: {
      const auto v = n.getDoubles(f.key, 3, f.lo, f.hi);
      s.*f.vec3 = Eigen::Vector3d(v[0], v[1], v[2]);
      break;
    }
    case Kind::kEnum: {
      const std::string v = n.getEnum(f.key, *f.names);
      f.set_index(s, static_cast<int>(std::find(f.names->begin(), f.names->end(), v) - f.names->begin()));
      break;
    }
    case Kind::kPath: s.*f.text = n.getPath(f.key); break;
  }
}

/// The keys of one options table given in section n, in the table's order; a key not given keeps the
/// member's value (the preset's or the default), but a key of `required` must be given.
template <class S>
void parseFields(const Node& n, S& s, const std::vector<options::Field<S>>& table,
                 std::initializer_list<const char*> required = {}) {
  for (const auto& f : table) {
    const bool must =
        std::any_of(required.begin(), required.end(), [&](const char* k) { return f.key == std::string(k); });
    if (must || n.has(f.key)) parseField(n, s, f);
  }
}

/// The keys a section accepts: `before` (subsections, keys read by hand), then its table's.
template <class S>
std::vector<std::string> keysOf(const std::vector<options::Field<S>>& table, std::vector<std::string> before = {}) {
  for (const auto& f : table) before.emplace_back(f.key);
  return before;
}

/// A section of only table keys: an unknown key is refused with the accepted list.
template <class S>
void parseSection(const Node& n, S& s, const std::vector<options::Field<S>>& table) {
  n.rejectUnknownKeysIn(keysOf(table));
  parseFields(n, s, table);
}

/// Text as one Markdown table cell: a '|' would end the cell.
inline std::string markdownCell(const std::string& text) {
  std::string out;
  for (const char c : text) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

/// One docs-table row per key of the table: | `prefix.key` | `member` | unit | range | default | meaning |,
/// the default being the member's value in `defaults`, "(required)" for a key of `required`.
template <class S>
std::string markdownRows(const std::string& prefix, const std::vector<options::Field<S>>& table, const S& defaults,
                         std::initializer_list<const char*> required = {}) {
  std::ostringstream s;
  for (const auto& f : table) {
    const bool must =
        std::any_of(required.begin(), required.end(), [&](const char* k) { return f.key == std::string(k); });
    s << "| `" << prefix << f.key << "` | `" << f.field << "` | " << f.unit << " | " << options::rangeText(f) << " | "
      << (must ? "(required)" : options::valueText(f, defaults)) << " | " << markdownCell(f.doc) << " |\n";
  }
  return s.str();
}

/// The header of the tables markdownRows fills.
inline std::string markdownHeader() {
  return "| key | member | unit | range | default | meaning |\n| --- | --- | --- | --- | --- | --- |\n";
}

}  // namespace omnislam::config
