// The frame of every process's main(): runs the body, turns a config error, a bad flag or an
// input the program refuses (std::invalid_argument) into exit code 2 with a message naming the
// key or the problem, any other failure into exit code 1, and never lets an exception escape.
#pragma once

#include <functional>
#include <string>

namespace omnislam::app {

/// Exit codes shared by all processes: kBadConfig is a bad config, flag or input, refused.
enum ExitCode : int { kOk = 0, kFailure = 1, kBadConfig = 2 };

/// Runs body(); prints "<prog>: <message>" on failure.
int runMain(const std::string& prog, const std::function<int()>& body);

/// LCM URL to use: the flag if given, else LCM_DEFAULT_URL, else LCM's default.
std::string lcmUrl(const std::string& flag_value);

}  // namespace omnislam::app
