// Checked YAML access: see yaml_node.h.
#include "omnislam/config/yaml_node.h"

#include <algorithm>
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/parser.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

namespace omnislam::config {
namespace {

std::string lineOf(const YAML::Node& n) {
  const YAML::Mark m = n.Mark();
  if (m.line < 0) return "";
  return " (line " + std::to_string(m.line + 1) + ")";
}

/// rejectRepeatedKeys below; `containers` holds the positions of the maps and lists met so far.
void walkRepeatedKeys(const YAML::Node& n, const std::string& source, const std::string& path,
                      std::set<int>& containers) {
  // An alias (*name) of a map or list is the anchored node itself, met again at its own position.
  // Nine lines of nested aliases expand to a billion nodes (every loader hung on 486 bytes), and no
  // config needs them: refused. (Aliases of single values are harmless and stay allowed.)
  if ((n.IsMap() || n.IsSequence()) && n.Mark().pos >= 0 && !containers.insert(n.Mark().pos).second)
    throw ConfigError(source + ": key '" + (path.empty() ? std::string() : path.substr(0, path.size() - 1)) +
                      "' repeats the " + (n.IsMap() ? "map" : "list") + " of line " +
                      std::to_string(n.Mark().line + 1) +
                      " through an alias (*name); aliases of maps and lists are not accepted");
  if (n.IsMap()) {
    std::map<std::string, int> first_line;
    for (auto it = n.begin(); it != n.end(); ++it) {
      const std::string key = it->first.IsScalar() ? it->first.Scalar() : std::string("?");
      const int line = it->first.Mark().line + 1;
      const auto [seen, fresh] = first_line.emplace(key, line);
      if (!fresh)
        throw ConfigError(source + ": key '" + path + key + "' is given twice (lines " + std::to_string(seen->second) +
                          " and " + std::to_string(line) + "); give it once");
      walkRepeatedKeys(it->second, source, path + key + ".", containers);
    }
  } else if (n.IsSequence()) {
    for (std::size_t i = 0; i < n.size(); ++i) {
      std::string p = path;
      if (!p.empty()) p.pop_back();  // "a.b." -> "a.b"
      walkRepeatedKeys(n[i], source, p + "[" + std::to_string(i) + "].", containers);
    }
  }
}

/// Throws ConfigError for a key given twice in one map, anywhere below `n` (yaml-cpp keeps both and
/// lookups return the first, so an override appended at the end of a file would be silently ignored),
/// and for an alias of a map or list.
void rejectRepeatedKeys(const YAML::Node& n, const std::string& source, const std::string& path) {
  std::set<int> containers;
  walkRepeatedKeys(n, source, path, containers);
}

/// The events of a YAML stream reduced to what onlyDocument needs: the documents begun, and where
/// the first node of a later document is (one that holds anything: an empty one after '---' is fine).
class LaterDocuments : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark&) override { ++documents; }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark& m, YAML::anchor_t) override { note(m); }
  void OnScalar(const YAML::Mark& m, const std::string&, YAML::anchor_t, const std::string&) override { note(m); }
  void OnSequenceStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    note(m);
  }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    note(m);
  }
  void OnMapEnd() override {}

  std::ptrdiff_t documents = 0;
  std::optional<YAML::Mark> later;  ///< the first node of a document after the first

 private:
  void note(const YAML::Mark& m) {
    if (documents > 1 && !later) later = m;
  }
};

/// The first document of `text`; a later one that holds anything is refused (yaml-cpp's Load reads
/// only the first, so everything after a '---' line would be ignored without a word). Not LoadAll:
/// yaml-cpp 0.7's LoadAll never ends on a stray ',' (the 1-byte file ","), appending empty documents
/// until memory runs out (jbeder/yaml-cpp#1040; fixed upstream by #1319, after Debian's 0.7.0; found
/// by tests/fuzz). The documents are counted here instead, at most one per line ('---' starts a
/// line) plus one: a parse that reaches that bound is the runaway one, and refused.
YAML::Node onlyDocument(const std::string& text, const std::string& source) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  LaterDocuments scan;
  const std::ptrdiff_t max_documents = std::count(text.begin(), text.end(), '\n') + 2;
  while (scan.documents < max_documents && !scan.later && parser.HandleNextDocument(scan)) {
  }
  if (!scan.later && scan.documents >= max_documents)
    throw ConfigError(source +
                      ": not valid YAML: the parser does not advance past a stray ',' (one outside a [list] "
                      "or {map})");
  if (scan.later)
    throw ConfigError(source + ": a second YAML document starts near line " + std::to_string(scan.later->line + 1) +
                      " (after a '---' line); a config is one document: join them or remove the '---'");
  return YAML::Load(text);
}

/// yaml-cpp's message, except for its nesting guard, whose message (0.7) is "bad file".
std::string yamlError(const YAML::Exception& e) {
  if (const auto* deep = dynamic_cast<const YAML::DeepRecursion*>(&e))
    return "nested too deeply (the parser stops at " + std::to_string(deep->depth()) + " levels) at line " +
           std::to_string(deep->mark.line + 1);
  return e.what();
}

std::string fmt(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace

Node::Node(YAML::Node node, std::shared_ptr<const std::string> source, std::string path,
           std::shared_ptr<const Overrides> overrides)
    : node_(std::move(node)), source_(std::move(source)), path_(std::move(path)), overrides_(std::move(overrides)) {}

std::string Node::origin(const std::string& key, const YAML::Node& n) const {
  if (overrides_) {
    // The key itself, or a map or list above it, set by an override (e.g. "filter.motion={...}").
    for (std::string k = keyPath(key); !k.empty();) {
      const auto it = overrides_->find(k);
      if (it != overrides_->end()) return " (from the override '" + it->second + "')";
      const auto cut = k.back() == ']' ? k.rfind('[') : k.rfind('.');
      if (cut == std::string::npos || cut == 0) break;
      k.erase(cut);
    }
  }
  return lineOf(n);
}

Node Node::loadFile(const std::string& path) {
  if (!std::filesystem::exists(path)) throw ConfigError(path + ": file not found");
  // A folder (or a device) would fail inside the stream with an exception that names no file.
  if (!std::filesystem::is_regular_file(path)) throw ConfigError(path + ": not a file");
  try {
    std::ifstream file(path, std::ios::binary);
    std::ostringstream text;
    text << file.rdbuf();
    YAML::Node root = onlyDocument(text.str(), path);
    if (!root.IsMap()) throw ConfigError(path + ": the top level must be a map of keys");
    rejectRepeatedKeys(root, path, "");
    return Node(root, std::make_shared<const std::string>(path), "");
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ": not valid YAML: " + yamlError(e));
  }
}

Node Node::loadFileWithOverrides(const std::string& path, const std::vector<std::string>& overrides) {
  Node n = loadFile(path);
  YAML::Node root = n.node_;
  auto origins = std::make_shared<Overrides>();
  for (const std::string& ov : overrides) {
    const auto eq = ov.find('=');
    const std::string key = ov.substr(0, eq);
    if (eq == std::string::npos || key.empty() || key.front() == '.' || key.back() == '.' ||
        key.find("..") != std::string::npos)
      throw ConfigError("override '" + ov + "': expected dotted.key=value");
    YAML::Node value;
    try {
      value = onlyDocument(ov.substr(eq + 1), "override '" + ov + "'");
    } catch (const YAML::Exception& e) {
      throw ConfigError("override '" + ov + "': the value is not valid YAML: " + yamlError(e));
    }
    rejectRepeatedKeys(value, "override '" + ov + "'", key + ".");  // the file's rules
    // Walk with fresh handles (YAML::Node assignment would rebind, not copy into, a handle).
    std::vector<std::string> parts;
    for (std::size_t b = 0;;) {
      const auto d = key.find('.', b);
      parts.push_back(key.substr(b, d == std::string::npos ? std::string::npos : d - b));
      if (d == std::string::npos) break;
      b = d + 1;
    }
    std::vector<YAML::Node> chain{root};
    for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
      YAML::Node next = chain.back()[parts[i]];
      if (next.IsDefined() && !next.IsMap() && !next.IsNull())
        throw ConfigError("override '" + ov + "': '" + parts[i] + "' is not a map of keys");
      if (!next.IsDefined() || next.IsNull()) chain.back()[parts[i]] = YAML::Node(YAML::NodeType::Map);
      chain.push_back(chain.back()[parts[i]]);
    }
    chain.back()[parts.back()] = value;
    (*origins)[key] = ov;  // a later override of the same key wins, as its value does
  }
  n.overrides_ = std::move(origins);
  return n;
}

Node Node::loadString(const std::string& text, const std::string& source) {
  try {
    YAML::Node root = onlyDocument(text, source);
    if (!root.IsMap()) throw ConfigError(source + ": the top level must be a map of keys");
    rejectRepeatedKeys(root, source, "");
    return Node(root, std::make_shared<const std::string>(source), "");
  } catch (const YAML::Exception& e) {
    throw ConfigError(source + ": not valid YAML: " + yamlError(e));
  }
}

std::string Node::sourceDir() const {
  const auto parent = std::filesystem::path(*source_).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

std::string Node::keyPath(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

std::string Node::where(const std::string& key) const { return *source_ + ": key '" + keyPath(key) + "'"; }

void Node::fail(const std::string& key, const std::string& what) const {
  const YAML::Node n = node_[key];
  throw ConfigError(where(key) + " " + what + (n ? origin(key, n) : origin(key, node_)));
}

// A key written with no value ("particles:", "--set seed=") is present: its getter refuses it, so a
// value deleted by mistake never silently becomes the default.
bool Node::has(const std::string& key) const { return node_.IsMap() && node_[key].IsDefined(); }

void Node::failIfEmpty(const std::string& key, const char* required) const {
  if (!node_[key].IsNull()) return;
  // The line is the key's: an empty value's own mark is where the next line starts. (No YAML::Node
  // is assigned here: assigning to a handle that refers to a node rewrites that node.)
  const std::string what =
      " has no value (" + std::string(required) + "; remove the key to take its default, where it has one)";
  for (auto it = node_.begin(); it != node_.end(); ++it)
    if (it->first.IsScalar() && it->first.Scalar() == key)
      throw ConfigError(where(key) + what + origin(key, it->first));
  throw ConfigError(where(key) + what + origin(key, node_[key]));
}

Node Node::child(const std::string& key) const {
  if (!has(key)) fail(key, "is missing (a map of keys is required)");
  failIfEmpty(key, "a map of keys is required");
  const YAML::Node n = node_[key];
  if (!n.IsMap()) fail(key, "must be a map of keys");
  return Node(n, source_, keyPath(key), overrides_);
}

std::optional<Node> Node::optChild(const std::string& key) const {
  if (!has(key)) return std::nullopt;
  return child(key);
}

std::vector<Node> Node::items(const std::string& key) const {
  if (!has(key)) fail(key, "is missing (a list is required)");
  failIfEmpty(key, "a list is required");
  const YAML::Node n = node_[key];
  if (!n.IsSequence()) fail(key, "must be a list");
  std::vector<Node> out;
  for (size_t i = 0; i < n.size(); ++i) {
    if (!n[i].IsMap()) fail(key, "item " + std::to_string(i) + " must be a map of keys");
    out.push_back(Node(n[i], source_, keyPath(key) + "[" + std::to_string(i) + "]", overrides_));
  }
  return out;
}

YAML::Node Node::scalar(const std::string& key) const {
  if (!has(key)) fail(key, "is missing");
  failIfEmpty(key, "a single value is required");
  const YAML::Node n = node_[key];
  if (!n.IsScalar()) fail(key, "must be a single value");
  return n;
}

double Node::getDouble(const std::string& key, double lo, double hi, Open open) const {
  const YAML::Node n = scalar(key);
  const std::string range = std::string("a number in ") + (open == Open::kLow ? "(" : "[") + fmt(lo) + ", " + fmt(hi) +
                            (open == Open::kHigh ? ")" : "]");
  double v = 0.0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    fail(key, "must be " + range + ", got '" + n.Scalar() + "'");
  }
  const bool outside = v < lo || v > hi || (open == Open::kLow && v == lo) || (open == Open::kHigh && v == hi);
  if (!std::isfinite(v) || outside) fail(key, "must be " + range + ", got " + n.Scalar());
  return v;
}

double Node::getDouble(const std::string& key, double lo, double hi, double def, Open open) const {
  return has(key) ? getDouble(key, lo, hi, open) : def;
}

int64_t Node::getInt(const std::string& key, int64_t lo, int64_t hi) const {
  const YAML::Node n = scalar(key);
  const std::string range = "a whole number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  // Decimal digits only, as a person reads them: yaml-cpp would take "0100" as octal 64 and "0x10"
  // as 16 (doubles have no such reading, so "010" would be 10 there and 8 here).
  const std::string& text = n.Scalar();
  const char* first = text.data() + (!text.empty() && text.front() == '+' ? 1 : 0);
  const char* last = text.data() + text.size();
  int64_t v = 0;
  const auto [end, ec] = std::from_chars(first, last, v, 10);
  if (ec != std::errc() || end != last || first == last) fail(key, "must be " + range + ", got '" + text + "'");
  if (v < lo || v > hi) fail(key, "must be " + range + ", got " + text);
  return v;
}

int64_t Node::getInt(const std::string& key, int64_t lo, int64_t hi, int64_t def) const {
  return has(key) ? getInt(key, lo, hi) : def;
}

bool Node::getBool(const std::string& key) const {
  const YAML::Node n = scalar(key);
  try {
    return n.as<bool>();
  } catch (const YAML::Exception&) {
    fail(key, "must be true or false, got '" + n.Scalar() + "'");
  }
}

bool Node::getBool(const std::string& key, bool def) const { return has(key) ? getBool(key) : def; }

std::string Node::getString(const std::string& key) const { return scalar(key).Scalar(); }

std::string Node::getString(const std::string& key, const std::string& def) const {
  return has(key) ? getString(key) : def;
}

std::string Node::getEnum(const std::string& key, const std::vector<std::string>& allowed) const {
  const std::string v = getString(key);
  for (const auto& a : allowed)
    if (a == v) return v;
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
  fail(key, "must be one of {" + list + "}, got '" + v + "'");
}

std::string Node::getEnum(const std::string& key, const std::vector<std::string>& allowed,
                          const std::string& def) const {
  return has(key) ? getEnum(key, allowed) : def;
}

std::vector<double> Node::getDoubles(const std::string& key, size_t n, double lo, double hi) const {
  if (!has(key)) fail(key, "is missing");
  failIfEmpty(key, "a list of numbers is required");
  const YAML::Node s = node_[key];
  const std::string what = "a list of " + std::to_string(n) + " numbers in [" + fmt(lo) + ", " + fmt(hi) + "]";
  if (!s.IsSequence() || s.size() != n) fail(key, "must be " + what);
  std::vector<double> out;
  for (size_t i = 0; i < n; ++i) {
    double v = 0.0;
    try {
      v = s[i].as<double>();
    } catch (const YAML::Exception&) {
      fail(key, "must be " + what + ", item " + std::to_string(i) + " is '" + s[i].Scalar() + "'");
    }
    if (!std::isfinite(v) || v < lo || v > hi)
      fail(key, "must be " + what + ", item " + std::to_string(i) + " is " + s[i].Scalar());
    out.push_back(v);
  }
  return out;
}

std::vector<std::string> Node::getStrings(const std::string& key) const {
  if (!has(key)) fail(key, "is missing");
  failIfEmpty(key, "a non-empty list is required");
  const YAML::Node s = node_[key];
  if (!s.IsSequence() || s.size() == 0) fail(key, "must be a non-empty list");
  std::vector<std::string> out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (!s[i].IsScalar()) fail(key, "item " + std::to_string(i) + " must be a single value");
    out.push_back(s[i].Scalar());
  }
  return out;
}

std::vector<std::string> Node::keys() const {
  std::vector<std::string> out;
  for (const auto& kv : node_) out.push_back(kv.first.Scalar());
  return out;
}

std::string Node::getPath(const std::string& key) const {
  const std::filesystem::path p(getString(key));
  if (p.is_absolute()) return p.string();
  return (std::filesystem::path(sourceDir()) / p).lexically_normal().string();
}

std::string Node::getExistingFile(const std::string& key) const {
  const std::string path = getPath(key);
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  std::string why;
  if (!std::filesystem::exists(st)) why = "does not exist";
  else if (std::filesystem::is_directory(st)) why = "is a directory, not a file";
  else if (!std::ifstream(path).good()) why = "cannot be read";
  if (!why.empty()) throw ConfigError(where(key) + " '" + path + "' " + why);
  return path;
}

void Node::rejectUnknownKeys(std::initializer_list<const char*> known) const {
  rejectUnknownKeysIn(std::vector<std::string>(known.begin(), known.end()));
}

void Node::rejectUnknownKeysIn(const std::vector<std::string>& known) const {
  for (const auto& kv : node_) {
    const std::string k = kv.first.Scalar();
    if (std::find(known.begin(), known.end(), k) != known.end()) continue;
    std::string list;
    for (const auto& c : known) list += (list.empty() ? "" : ", ") + c;
    throw ConfigError(where(k) + " is not a known key (known here: " + list + ")" + origin(k, kv.first));
  }
}

}  // namespace omnislam::config
