// The main() frame of every process (app.h) and the flag checks (cli.h): each kind of failure
// becomes its exit code and one line that says what kind it is; NaN is not in any range.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "omnislam/config/yaml_node.h"
#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"

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

namespace {

int parseRate(const std::string& value, double& rate) {
  CLI::App cli("test");
  cli.add_option("--rate-hz", rate)->check(app::FiniteRange(0.01, 1000.0));
  std::vector<std::string> args{"prog", "--rate-hz", value};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::ostringstream captured;  // CLI11 prints its error line to cerr
  std::streambuf* old = std::cerr.rdbuf(captured.rdbuf());
  const int rc = app::parseFlags(cli, static_cast<int>(argv.size()), argv.data());
  std::cerr.rdbuf(old);
  return rc;
}

// CLI11's Range lets NaN through (NaN < min and NaN > max are both false): --rate-hz nan gave a
// frame period of LLONG_MIN us and images stamped with negative utimes.
TEST(FiniteRange, RefusesNanInfinityAndOutOfRangeAcceptsTheBounds) {
  for (const char* bad : {"nan", "NaN", "-nan", "inf", "-inf", "1e400", "0.001", "1000.5", "fast"}) {
    double rate = 1.0;
    EXPECT_EQ(parseRate(bad, rate), app::kBadConfig) << bad;
  }
  for (const auto& [good, expected] : {std::pair{"0.01", 0.01}, std::pair{"1000", 1000.0}, std::pair{"2.5", 2.5}}) {
    double rate = 1.0;
    EXPECT_EQ(parseRate(good, rate), -1) << good;
    EXPECT_EQ(rate, expected) << good;
  }
  // CLI11's own Range, for the record: it takes NaN.
  CLI::App cli("test");
  double rate = 1.0;
  cli.add_option("--rate-hz", rate)->check(CLI::Range(0.01, 1000.0));
  std::vector<std::string> args{"prog", "--rate-hz", "nan"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  EXPECT_NO_THROW(cli.parse(static_cast<int>(argv.size()), argv.data()));
  EXPECT_TRUE(std::isnan(rate));
}

}  // namespace

namespace {

int parseSeed(const std::string& value, std::uint64_t& seed) {
  CLI::App cli("test");
  cli.add_option("--seed", seed)->check(app::SeedRange());
  std::vector<std::string> args{"prog", "--seed", value};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  std::ostringstream captured;
  std::streambuf* old = std::cerr.rdbuf(captured.rdbuf());
  const int rc = app::parseFlags(cli, static_cast<int>(argv.size()), argv.data());
  std::cerr.rdbuf(old);
  return rc;
}

// CLI11 reads "-1" into a uint64_t as 2^64 - 1 without a word: a user asking for seed -1 got
// seed 18446744073709551615. Seeds take what the config files' `seed` keys take.
TEST(SeedRange, RefusesNegativeFractionalAndTooLargeAcceptsTheBounds) {
  for (const char* bad :
       {"-1", "-0", "1.5", "1e3", "", " 1", "0x10", "9223372036854775808", "99999999999999999999", "seven"}) {
    std::uint64_t seed = 5;
    EXPECT_EQ(parseSeed(bad, seed), app::kBadConfig) << "'" << bad << "'";
    EXPECT_EQ(seed, 5u) << bad;
  }
  for (const auto& [good, expected] :
       {std::pair{"0", 0ull}, std::pair{"1", 1ull}, std::pair{"9223372036854775807", 9223372036854775807ull}}) {
    std::uint64_t seed = 5;
    EXPECT_EQ(parseSeed(good, seed), -1) << good;
    EXPECT_EQ(seed, expected) << good;
  }
}

}  // namespace
