// Checked access to YAML config files: every getter validates type and range and, on failure,
// throws ConfigError naming the file, the full key path, the accepted range and the line.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <initializer_list>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace omnislam::config {

/// A broken config contract: the message names file, key, accepted range and what was found.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A YAML map node together with where it came from (file name and key path), so that every
/// error can say exactly which key is wrong.
class Node {
 public:
  /// Parses a file; throws ConfigError if it cannot be read or is not valid YAML.
  static Node loadFile(const std::string& path);
  /// Parses a file, then applies `overrides`, each "dotted.key=value" (the value is read as YAML,
  /// so "1.0", "true", "ml" and "[1, 2, 3]" work; missing maps on the path are created). The source
  /// stays the file (relative paths resolve against it); a malformed override throws ConfigError
  /// naming it. Unknown keys are caught later by the parser's rejectUnknownKeys, as in the file.
  static Node loadFileWithOverrides(const std::string& path, const std::vector<std::string>& overrides);
  /// Parses text; `source` names it in messages (e.g. the file name).
  static Node loadString(const std::string& text, const std::string& source);

  const std::string& source() const { return *source_; }
  /// Dotted path of this node from the document root ("" for the root).
  const std::string& path() const { return path_; }
  /// Directory of the source file (for resolving relative paths), "." for strings.
  std::string sourceDir() const;

  /// The key is in this map, also when written with no value ("particles:"): every getter then
  /// refuses it, rather than taking the default for a value deleted by mistake.
  bool has(const std::string& key) const;
  /// Required map child; throws if missing or not a map.
  Node child(const std::string& key) const;
  /// Optional map child.
  std::optional<Node> optChild(const std::string& key) const;
  /// Items of a required sequence of maps.
  std::vector<Node> items(const std::string& key) const;

  /// Which end of a range is excluded: a value that must be strictly above lo (kLow: (lo, hi]) or
  /// strictly below hi (kHigh: [lo, hi)); messages print the range so.
  enum class Open { kNone, kLow, kHigh };
  double getDouble(const std::string& key, double lo, double hi, Open open = Open::kNone) const;
  double getDouble(const std::string& key, double lo, double hi, double def, Open open = Open::kNone) const;
  int64_t getInt(const std::string& key, int64_t lo, int64_t hi) const;
  int64_t getInt(const std::string& key, int64_t lo, int64_t hi, int64_t def) const;
  bool getBool(const std::string& key) const;
  bool getBool(const std::string& key, bool def) const;
  std::string getString(const std::string& key) const;
  std::string getString(const std::string& key, const std::string& def) const;
  /// A string that must be one of `allowed`.
  std::string getEnum(const std::string& key, const std::vector<std::string>& allowed) const;
  std::string getEnum(const std::string& key, const std::vector<std::string>& allowed, const std::string& def) const;
  /// A sequence of exactly `n` numbers, each in [lo, hi].
  std::vector<double> getDoubles(const std::string& key, size_t n, double lo, double hi) const;
  /// A non-empty sequence of scalars, as strings.
  std::vector<std::string> getStrings(const std::string& key) const;
  /// The keys of this map, in file order.
  std::vector<std::string> keys() const;
  /// A path; relative paths are resolved against the source file's directory.
  std::string getPath(const std::string& key) const;
  /// getPath() of a file that must exist and be readable now; otherwise ConfigError naming the key
  /// and the resolved path ("file.yaml: camera.world: '/x/w.yaml' does not exist"), checked at start.
  std::string getExistingFile(const std::string& key) const;

  /// Throws if the map has a key not in `known` (catches typos such as "sigm_px").
  void rejectUnknownKeys(std::initializer_list<const char*> known) const;
  /// The same for a list built at run time (the keys of an options table, options_table.h).
  void rejectUnknownKeysIn(const std::vector<std::string>& known) const;

  /// "file: key 'a.b' " prefix used in messages.
  std::string where(const std::string& key) const;

 private:
  /// Dotted key path -> the override ("key=value") that set it, for messages.
  using Overrides = std::map<std::string, std::string>;
  Node(YAML::Node node, std::shared_ptr<const std::string> source, std::string path,
       std::shared_ptr<const Overrides> overrides = nullptr);
  /// " (line N)" of the node at `key` in the file, or " (from the override 'k=v')" when an
  /// override set that key or a map above it.
  std::string origin(const std::string& key, const YAML::Node& n) const;
  YAML::Node scalar(const std::string& key) const;
  std::string keyPath(const std::string& key) const;
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;
  /// fail() when the key was written with no value; `required` says what it needs.
  void failIfEmpty(const std::string& key, const char* required) const;

  YAML::Node node_;
  std::shared_ptr<const std::string> source_;
  std::string path_;
  std::shared_ptr<const Overrides> overrides_;
};

}  // namespace omnislam::config
