// Command-line parsing shared by every process and tool: CLI11, with a bad flag or flag value
// turned into exit code 2 (app::kBadConfig) like a bad config file, instead of CLI11's own codes
// (105 for a value out of range, 106 for a wrong type, ...). --help still exits 0.
#pragma once

#include <CLI/CLI.hpp>

#include "omnislam/lcmio/app.h"

namespace omnislam::app {

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
#define OMNISLAM_PARSE_FLAGS(cli, argc, argv)                                         \
  do {                                                                                \
    if (const int omnislam_rc_ = ::omnislam::app::parseFlags(cli, argc, argv); omnislam_rc_ >= 0) \
      return omnislam_rc_;                                                            \
  } while (false)
