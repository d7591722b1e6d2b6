// Checked YAML access: every error names the file, the key path, the accepted range and the line.
#include <gtest/gtest.h>

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
  EXPECT_NE(errorOf([&] { a.getDouble("b", 3.5, 10, Node::Open::kLow); }).find("must be a number in (3.5, 10], got 3.5"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { a.getDouble("b", 0, 3.5, Node::Open::kHigh); }).find("must be a number in [0, 3.5), got 3.5"),
            std::string::npos);
  EXPECT_DOUBLE_EQ(a.getDouble("missing", 0, 1, 1.0, Node::Open::kHigh), 1.0);  // a default is not checked
  EXPECT_NE(errorOf([&] { a.getInt("b", 0, 10); }).find("whole number"), std::string::npos);
  EXPECT_NE(errorOf([&] { a.getBool("flag"); }).find("true or false"), std::string::npos);
  EXPECT_NE(errorOf([&] { a.getDouble("nothere", 0, 1); }).find("'a.nothere' is missing"), std::string::npos);
  EXPECT_NE(errorOf([&] { a.getEnum("c", {"x", "y"}); }).find("one of {x, y}"), std::string::npos);
  EXPECT_NE(errorOf([&] { a.getDoubles("list", 3, 0, 9); }).find("a list of 3 numbers"), std::string::npos);
  EXPECT_NE(errorOf([&] { a.rejectUnknownKeys({"b", "c", "n", "flag"}); }).find("'a.list' is not a known key"),
            std::string::npos);
}

TEST(YamlNode, InvalidYamlAndMissingFilesAreConfigErrors) {
  EXPECT_NE(errorOf([] { Node::loadString("a: [1, 2", "bad.yaml"); }).find("bad.yaml: not valid YAML"),
            std::string::npos);
  EXPECT_NE(errorOf([] { Node::loadFile("/nonexistent/x.yaml"); }).find("file not found"), std::string::npos);
  EXPECT_NE(errorOf([] { Node::loadString("- 1\n- 2\n", "seq.yaml"); }).find("top level must be a map"),
            std::string::npos);
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

}  // namespace
