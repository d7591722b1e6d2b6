// The main() frame of every process (common/lcmio/include/omnislam/lcmio/app.h): each kind of
// failure becomes its exit code and one line on stderr that says what kind it is.
#include <gtest/gtest.h>

#include <iostream>
#include <sstream>
#include <stdexcept>

#include "omnislam/config/yaml_node.h"
#include "omnislam/lcmio/app.h"

using namespace omnislam;

namespace {

struct Outcome {
  int code = -1;
  std::string err;
};

Outcome run(const std::function<int()>& body) {
  std::ostringstream captured;
  std::streambuf* old = std::cerr.rdbuf(captured.rdbuf());
  Outcome r;
  r.code = app::runMain("prog", body);
  std::cerr.rdbuf(old);
  r.err = captured.str();
  return r;
}

TEST(RunMain, EachKindOfFailureHasItsExitCodeAndOneLine) {
  EXPECT_EQ(run([] { return 0; }).code, app::kOk);
  EXPECT_EQ(run([] { return 7; }).code, 7) << "the body's own code is passed on";

  const Outcome config = run([]() -> int { throw config::ConfigError("f.yaml: key 'a' must be in [0, 1]"); });
  EXPECT_EQ(config.code, app::kBadConfig);
  EXPECT_EQ(config.err, "prog: config error: f.yaml: key 'a' must be in [0, 1]\n");

  // A refused input is not a "setting": the line says error, the code is still 2.
  const Outcome input = run([]() -> int { throw std::invalid_argument("run.lcm: no SLAM_POSE message"); });
  EXPECT_EQ(input.code, app::kBadConfig);
  EXPECT_EQ(input.err, "prog: error: run.lcm: no SLAM_POSE message\n");

  const Outcome fatal = run([]() -> int { throw std::runtime_error("disk full"); });
  EXPECT_EQ(fatal.code, app::kFailure);
  EXPECT_EQ(fatal.err, "prog: fatal: disk full\n");

  const Outcome unknown = run([]() -> int { throw 42; });
  EXPECT_EQ(unknown.code, app::kFailure);
  EXPECT_EQ(unknown.err, "prog: fatal: an unknown exception\n");
}

}  // namespace
