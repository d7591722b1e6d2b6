// main() frame shared by the processes: see app.h.
#include "omnislam/lcmio/app.h"

#include <cstdlib>
#include <exception>
#include <iostream>

#include "omnislam/config/yaml_node.h"

namespace omnislam::app {

int runMain(const std::string& prog, const std::function<int()>& body) {
  try {
    return body();
  } catch (const config::ConfigError& e) {
    std::cerr << prog << ": config error: " << e.what() << std::endl;
    return kBadConfig;
  } catch (const std::invalid_argument& e) {
    // A flag or option out of range, or an input the program cannot work on (a log without the
    // messages it needs): the message says which; "invalid setting" misnamed the second kind.
    std::cerr << prog << ": error: " << e.what() << std::endl;
    return kBadConfig;
  } catch (const std::exception& e) {
    std::cerr << prog << ": fatal: " << e.what() << std::endl;
    return kFailure;
  } catch (...) {
    std::cerr << prog << ": fatal: an unknown exception" << std::endl;
    return kFailure;
  }
}

std::string lcmUrl(const std::string& flag_value) {
  if (!flag_value.empty()) return flag_value;
  if (const char* env = std::getenv("LCM_DEFAULT_URL")) return env;
  return "";
}

}  // namespace omnislam::app
