// Command-line parsing shared by every process and tool: CLI11, with a bad flag or flag value
// turned into exit code 2 (app::kBadConfig) like a bad config file, instead of CLI11's own codes
// (105 for a value out of range, 106 for a wrong type, ...). --help still exits 0.
#pragma once

#include <CLI/CLI.hpp>
#include <sstream>
#include <string>

#include "omnislam/lcmio/app.h"

namespace omnislam::app {

/// CLI::Range for a real-valued flag that also refuses NaN: CLI11's Range tests only
/// "v < min || v > max", which NaN passes (e.g. --rate-hz nan gave a frame period of LLONG_MIN us).
/// The message names the range as CLI11's does.
inline CLI::Validator FiniteRange(double min, double max) {
  std::ostringstream name;
  name << "FLOAT in [" << min << " - " << max << "]";
  return CLI::Validator(
      [min, max](std::string& input) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(input, v)) return "Value " + input + " could not be converted";
        if (!(v >= min && v <= max)) {  // false for NaN
          std::ostringstream o;
          o << "Value " << input << " not in range [" << min << " - " << max << "]";
          return o.str();
        }
        return std::string();
      },
      name.str());
}

/// A seed flag: a whole number in [0, 2^63 - 1], the range the config files' `seed` keys accept.
/// CLI11 reads "-1" into a uint64_t as 2^64 - 1 without a word; this refuses it, naming the range.
inline CLI::Validator SeedRange() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        const bool digits =
            !input.empty() && input.size() <= 19 && input.find_first_not_of("0123456789") == std::string::npos;
        if (!digits || (input.size() == 19 && input > "9223372036854775807"))
          return "Value " + input + " not in range [0 - 9223372036854775807] (a whole number)";
        return std::string();
      },
      "UINT in [0 - 9223372036854775807]");
}

/// Parses argv; returns -1 to go on, or the exit code to return from main() (CLI11 has printed the
/// help or the one-line error naming the flag and its accepted range).
inline int parseFlags(CLI::App& cli, int argc, char** argv) {
  try {
    cli.parse(argc, argv);
    return -1;
  } catch (const CLI::ParseError& e) {
    const int rc = cli.exit(e);
    return rc == 0 ? kOk : kBadConfig;
  }
}

}  // namespace omnislam::app

/// Drop-in for CLI11_PARSE: returns from main() with 0 (help) or 2 (bad flag).
#define OMNISLAM_PARSE_FLAGS(cli, argc, argv)                                                                          \
  do {                                                                                                                 \
    if (const int omnislam_rc_ = ::omnislam::app::parseFlags(cli, argc, argv); omnislam_rc_ >= 0) return omnislam_rc_; \
  } while (false)
