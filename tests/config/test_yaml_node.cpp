// Checked YAML access: every error names the file, the key path, the accepted range and the line.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include "omnislam/config/world_config.h"
#include "omnislam/config/yaml_node.h"

using omnislam::config::ConfigError;
using omnislam::config::Node;

namespace {

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(YamlNode, GettersCheckTypeAndRangeAndNameTheKey) {
  const Node root = Node::loadString("a:\n  b: 3.5\n  c: text\n  n: 7\n  flag: maybe\n  list: [1, 2]\n", "cfg.yaml");
  const Node a = root.child("a");
  EXPECT_DOUBLE_EQ(a.getDouble("b", 0, 10), 3.5);
  EXPECT_EQ(a.getInt("n", 0, 10), 7);
  EXPECT_DOUBLE_EQ(a.getDouble("missing", 0, 10, 1.25), 1.25);
  const std::string range = errorOf([&] { a.getDouble("b", 0, 1); });
  EXPECT_NE(range.find("cfg.yaml: key 'a.b' must be a number in [0, 1], got 3.5 (line 2)"), std::string::npos) << range;
  EXPECT_NE(errorOf([&] { a.getDouble("c", 0, 1); }).find("got 'text'"), std::string::npos);
  // Open ends: the end itself is refused and the message prints the range as it is.
  EXPECT_DOUBLE_EQ(a.getDouble("b", 0, 3.5, Node::Open::kLow), 3.5);
  EXPECT_DOUBLE_EQ(a.getDouble("b", 3.5, 10, Node::Open::kHigh), 3.5);
  EXPECT_NE(
      errorOf([&] { a.getDouble("b", 3.5, 10, Node::Open::kLow); }).find("must be a number in (3.5, 10], got 3.5"),
      std::string::npos);
  EXPECT_NE(errorOf([&] { a.getDouble("b", 0, 3.5, Node::Open::kHigh); }).find("must be a number in [0, 3.5), got 3.5"),
            std::string::npos);
  EXPECT_DOUBLE_EQ(a.getDouble("missing", 0, 1, 1.0, Node::Open::kHigh), 1.0);  // a default is not checked
  EXPECT_NE(errorOf([&] { a.getInt("b", 0, 10); }).find("whole number"), std::string::npos);
  EXPECT_NE(errorOf([&] { a.getBool("flag"); }).find("true or false"), std::string::npos);
  EXPECT_NE(errorOf([&] { a.getDouble("nothere", 0, 1); }).find("'a.nothere' is missing"), std::string::npos);
  EXPECT_NE(errorOf([&] { a.getEnum("c", {"x", "y"}); }).find("one of {x, y}"), std::string::npos);
  EXPECT_NE(errorOf([&] { a.getDoubles("list", 3, 0, 9); }).find("a list of 3 numbers"), std::string::npos);
  EXPECT_NE(errorOf([&] {
              a.rejectUnknownKeys({"b", "c", "n", "flag"});
            }).find("'a.list' is not a known key"),
            std::string::npos);
}

TEST(YamlNode, InvalidYamlAndMissingFilesAreConfigErrors) {
  EXPECT_NE(errorOf([] { Node::loadString("a: [1, 2", "bad.yaml"); }).find("bad.yaml: not valid YAML"),
            std::string::npos);
  EXPECT_NE(errorOf([] { Node::loadFile("/nonexistent/x.yaml"); }).find("file not found"), std::string::npos);
  EXPECT_NE(errorOf([] { Node::loadString("- 1\n- 2\n", "seq.yaml"); }).find("top level must be a map"),
            std::string::npos);
  // yaml-cpp's nesting guard said only "bad file".
  const std::string deep =
      errorOf([] { Node::loadString("a: " + std::string(3000, '[') + std::string(3000, ']'), "deep.yaml"); });
  EXPECT_NE(deep.find("deep.yaml: not valid YAML: nested too deeply (the parser stops at "), std::string::npos) << deep;
  EXPECT_NE(deep.find(" levels) at line 1"), std::string::npos) << deep;
}

// A key given twice in one map: yaml-cpp keeps both and lookups return the first, so an override
// appended at the end of a file would be silently ignored.
TEST(YamlNode, AKeyGivenTwiceIsRefusedWithBothLines) {
  EXPECT_NE(errorOf([] {
              Node::loadString("rate: 50\nname: x\nrate: 1000\n", "w.yaml");
            }).find("w.yaml: key 'rate' is given twice (lines 1 and 3)"),
            std::string::npos);
  const std::string nested =
      errorOf([] { Node::loadString("a:\n  list:\n    - {x: 1, y: 2}\n    - {x: 1, x: 2}\n", "n.yaml"); });
  EXPECT_NE(nested.find("n.yaml: key 'a.list[1].x' is given twice (lines 4 and 4)"), std::string::npos) << nested;
  // The same key in different maps is fine.
  EXPECT_EQ(errorOf([] { Node::loadString("a: {x: 1}\nb: {x: 1}\n", "ok.yaml"); }), "");
}

// Nested aliases of lists or maps expand exponentially: nine lines of them took every loader past
// two minutes (a helper's fuzzing). They are refused at once, naming the key and the line; an
// alias of a single value stays allowed. A folder given as the file is a ConfigError naming it.
TEST(YamlNode, AliasesOfListsAndMapsAndFoldersAreRefused) {
  std::string laughs = "l0: &l0 \"lol\"\n";
  for (int i = 1; i <= 9; ++i) {
    laughs += "l" + std::to_string(i) + ": &l" + std::to_string(i) + " [";
    for (int k = 0; k < 10; ++k) laughs += std::string(k ? ", " : "") + "*l" + std::to_string(i - 1);
    laughs += "]\n";
  }
  const std::string e = errorOf([&] { Node::loadString(laughs, "laughs.yaml"); });
  EXPECT_NE(e.find("laughs.yaml: key 'l2[0]' repeats the list of line 2 through an alias"), std::string::npos) << e;
  const std::string m = errorOf([] { Node::loadString("a: &m {x: 1}\nb: *m\n", "m.yaml"); });
  EXPECT_NE(m.find("m.yaml: key 'b' repeats the map of line 1 through an alias"), std::string::npos) << m;
  EXPECT_EQ(errorOf([] { Node::loadString("a: &v 3\nb: *v\n", "scalar.yaml"); }), "");
  const std::string dir = errorOf([] { Node::loadFile("/tmp"); });
  EXPECT_EQ(dir, "/tmp: not a file");
  // Override values follow the file's rules.
  const std::string path = "/tmp/omnislam-yaml-node-override.yaml";
  std::ofstream(path) << "filter: {motion: {model: chord}}\n";
  const std::string twice = errorOf([&] { Node::loadFileWithOverrides(path, {"filter.motion={model: a, model: b}"}); });
  EXPECT_NE(twice.find("override 'filter.motion={model: a, model: b}': key 'filter.motion.model' is given twice"),
            std::string::npos)
      << twice;
  std::remove(path.c_str());
}

// A key written with no value is not absent ("particles:" or "--set seed=" must not take the
// default without a word); and yaml-cpp's Load reads only the first document, so everything after a
// '---' line would be ignored. Both are refused, naming the key or the line.
TEST(YamlNode, AKeyWithNoValueAndASecondDocumentAreRefused) {
  const Node root = Node::loadString("particles:\nmotion:\nlist:\nxs:\nnames:\nok: 3\n", "e.yaml");
  const std::string with_default = errorOf([&] { root.getInt("particles", 1, 100, 50); });
  EXPECT_NE(with_default.find("e.yaml: key 'particles' has no value (a single value is required; remove the key to "
                              "take its default, where it has one) (line 1)"),
            std::string::npos)
      << with_default;
  EXPECT_NE(errorOf([&] { root.getDouble("particles", 0, 1, 0.5); }).find("'particles' has no value"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { root.getBool("particles", true); }).find("'particles' has no value"), std::string::npos);
  EXPECT_NE(errorOf([&] { root.getString("particles", "x"); }).find("'particles' has no value"), std::string::npos);
  EXPECT_NE(errorOf([&] { root.getEnum("particles", {"a"}, "a"); }).find("'particles' has no value"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { root.optChild("motion"); }).find("'motion' has no value (a map of keys is required"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { root.items("list"); }).find("'list' has no value (a list is required"), std::string::npos);
  EXPECT_NE(errorOf([&] { root.getDoubles("xs", 2, 0, 1); }).find("'xs' has no value"), std::string::npos);
  EXPECT_NE(errorOf([&] { root.getStrings("names"); }).find("'names' has no value"), std::string::npos);
  EXPECT_TRUE(root.has("particles"));
  EXPECT_EQ(root.getInt("ok", 1, 5, 1), 3);
  EXPECT_EQ(root.getInt("absent", 1, 5, 1), 1);  // a key not written at all still takes its default

  const std::string path = "/tmp/omnislam-yaml-node-empty-" + std::to_string(::getpid()) + ".yaml";
  std::ofstream(path) << "seed: 4\n";
  const Node set = Node::loadFileWithOverrides(path, {"seed="});
  const std::string from_set = errorOf([&] { set.getInt("seed", 0, 100, 1); });
  EXPECT_NE(from_set.find("key 'seed' has no value"), std::string::npos) << from_set;
  EXPECT_NE(from_set.find("(from the override 'seed=')"), std::string::npos) << from_set;

  // Documents: a leading '---' and an empty trailing one are one document; a second with content
  // is refused, in a file, in a string and in an override's value.
  EXPECT_EQ(Node::loadString("---\na: 1\n---\n", "one.yaml").getInt("a", 0, 9), 1);
  const std::string two = errorOf([] { Node::loadString("a: 1\n---\nb: 2\n", "two.yaml"); });
  EXPECT_NE(two.find("two.yaml: a second YAML document starts near line 3 (after a '---' line); a config is one "
                     "document"),
            std::string::npos)
      << two;
  std::ofstream(path) << "seed: 4\n---\nseed: 5\n";
  EXPECT_NE(errorOf([&] { Node::loadFile(path); }).find(path + ": a second YAML document"), std::string::npos);
  std::ofstream(path) << "seed: 4\n";
  EXPECT_NE(errorOf([&] { Node::loadFileWithOverrides(path, {"seed=1\n---\n2"}); }).find("a second YAML document"),
            std::string::npos);
  std::remove(path.c_str());
}

// A stray ',' (found by tests/fuzz, regressions/world_config and saved_map): yaml-cpp 0.7's LoadAll
// never returned on it, appending empty documents until memory ran out (2.8 GB in 100 s). Now it is
// refused at once, in a string, a file and an override's value.
TEST(YamlNode, AStrayCommaIsRefusedNotParsedForever) {
  for (const char* text : {",", " ,\n", "{a: 1}, ", "a: 1\n---\n,\n"}) {
    SCOPED_TRACE(text);
    const std::string e = errorOf([&] { Node::loadString(text, "comma.yaml"); });
    EXPECT_EQ(e.rfind("comma.yaml: not valid YAML: the parser does not advance past a stray ','", 0), 0u) << e;
  }
  const std::string path = "/tmp/omnislam-yaml-node-comma-" + std::to_string(::getpid()) + ".yaml";
  std::ofstream(path) << "seed: 4\n,\n";
  EXPECT_NE(errorOf([&] { Node::loadFile(path); }).find(path + ": not valid YAML"), std::string::npos);
  std::ofstream(path) << "seed: 4\n";
  EXPECT_NE(errorOf([&] { Node::loadFileWithOverrides(path, {"seed=,"}); }).find("override 'seed=,'"),
            std::string::npos);
  std::remove(path.c_str());
}

// Whole numbers are decimal: YAML 1.1's octal and hexadecimal readings surprise ("0100" would be 64).
TEST(YamlNode, WholeNumbersAreDecimal) {
  const Node root = Node::loadString("a: 0100\nb: 0x10\nc: +7\nd: 12abc\ne: -3\n", "i.yaml");
  EXPECT_EQ(root.getInt("a", 0, 1000), 100);
  EXPECT_NE(errorOf([&] { root.getInt("b", 0, 1000); }).find("must be a whole number in [0, 1000], got '0x10'"),
            std::string::npos);
  EXPECT_EQ(root.getInt("c", 0, 10), 7);
  EXPECT_NE(errorOf([&] { root.getInt("d", 0, 1000); }).find("got '12abc'"), std::string::npos);
  EXPECT_EQ(root.getInt("e", -5, 5), -3);
  EXPECT_NE(errorOf([&] { root.getInt("e", 0, 5); }).find("got -3"), std::string::npos);
}

TEST(WorldConfig, ALightIdUsedTwiceIsRefused) {
  // The grid numbers its 16 lights 1..16; a listed light with id 2 made GROUND_TRUTH_MAP hold two
  // lights with id 2, and the evaluation's association scores ambiguous.
  std::ifstream in(std::string(OMNISLAM_SOURCE_DIR) + "/config/worlds/sports_hall.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string w = text.str();
  const std::string grid_y = "    y_m: [-5.5, -1.0, 3.5, 8.0]\n";
  ASSERT_NE(w.find(grid_y), std::string::npos);
  const std::string twice =
      std::string(w).replace(w.find(grid_y), grid_y.size(), grid_y + "  list: [{id: 2, x_m: 1.0, y_m: 1.0}]\n");
  const std::string e = errorOf([&] { omnislam::config::parseWorld(Node::loadString(twice, "w.yaml")); });
  EXPECT_NE(e.find("w.yaml: key 'lights.list"), std::string::npos) << e;
  EXPECT_NE(e.find("light id 2 is used twice"), std::string::npos) << e;
  // Without an id the listed light continues the numbering (17): accepted.
  const std::string next =
      std::string(w).replace(w.find(grid_y), grid_y.size(), grid_y + "  list: [{x_m: 1.0, y_m: 1.0}]\n");
  EXPECT_EQ(omnislam::config::parseWorld(Node::loadString(next, "w.yaml")).lights.back().id, 17);
}

// A grid is the product of its two lists: 3000 values each way would be 9 million lights, 10 000
// would ask for 3 GB. The lights go into GROUND_TRUTH_MAP, which holds at most 100 000.
TEST(WorldConfig, MoreLightsThanAMapCarriesAreRefusedBeforeTheGridIsBuilt) {
  auto values = [](int n) {
    std::string v = "[";
    for (int i = 0; i < n; ++i) v += (i ? ", " : "") + std::to_string(i);
    return v + "]";
  };
  auto world = [&](int nx, int ny, const std::string& list) {
    return "lights:\n  grid:\n    x_m: " + values(nx) + "\n    y_m: " + values(ny) + "\n" + list;
  };
  // parseLights is reached through parseWorld; only the lights' own error is looked for.
  std::string e = errorOf([&] { omnislam::config::parseWorld(Node::loadString(world(10000, 10000, ""), "w.yaml")); });
  EXPECT_NE(e.find("w.yaml: key 'lights.grid.x_m': a grid of 10000 x 10000 lights, more than 100000"),
            std::string::npos)
      << e;
  e = errorOf([&] {
    omnislam::config::parseWorld(Node::loadString(world(1000, 100, "  list: [{x_m: 1, y_m: 1}]\n"), "w.yaml"));
  });
  EXPECT_NE(e.find("w.yaml: key 'lights.list': 100000 lights in the grid and 1 in the list, more than 100000"),
            std::string::npos)
      << e;
  // 100 000 exactly is not refused by this check (the error, if any, is about another key).
  e = errorOf([&] { omnislam::config::parseWorld(Node::loadString(world(1000, 100, ""), "w.yaml")); });
  EXPECT_EQ(e.find("more than 100000"), std::string::npos) << e;
}

TEST(WorldConfig, TheSportsHallParsesToThePapersExperiment) {
  const auto w = omnislam::config::loadWorld(std::string(OMNISLAM_SOURCE_DIR) + "/config/worlds/sports_hall.yaml");
  EXPECT_EQ(w.lights.size(), 16u);
  for (const auto& L : w.lights) EXPECT_DOUBLE_EQ(L.p_LinW_m.z(), 6.5);
  EXPECT_DOUBLE_EQ(w.camera.mounting.z_m, 1.8);
  EXPECT_GE(w.truth_rate_hz, 20.0);
  EXPECT_DOUBLE_EQ(w.image_rate_hz, 1.0);
  EXPECT_NEAR(w.camera.intrinsics.max_zenith_rad * 2, 190.0 * M_PI / 180.0, 1e-12) << ">= 185 deg field of view";
}

// Issue 47: a config naming a file that is missing (a features config's world file) stops at start
// with the key, not only the path.
TEST(YamlNode, AMissingFileIsNamedByItsKey) {
  const std::string dir = ::testing::TempDir();
  const std::string present = dir + "/present_" + std::to_string(getpid()) + ".yaml";
  std::ofstream(present) << "x: 1\n";
  const Node root = Node::loadString(
      "camera:\n  world: " + present + "\n  missing: /nonexistent/w.yaml\n  dir: " + dir + "\n", "features.yaml");
  const Node cam = root.child("camera");
  EXPECT_EQ(cam.getExistingFile("world"), present);
  EXPECT_EQ(errorOf([&] { cam.getExistingFile("missing"); }),
            "features.yaml: key 'camera.missing' '/nonexistent/w.yaml' does not exist");
  EXPECT_NE(errorOf([&] { cam.getExistingFile("dir"); }).find("key 'camera.dir'"), std::string::npos);
  std::remove(present.c_str());
}

}  // namespace
