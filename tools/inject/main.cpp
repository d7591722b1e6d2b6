// omnislam-inject: a fault injector for a live bus. Takes the next real message of a channel (or
// the N-th with --skip), alters it (its utime shifted by --utime-offset-s, fields set with --set
// x=1e300, theta=nan, ...) and publishes it once on the same channel, then prints what it sent and
// exits. For checking that every process refuses, counts and reports a stray or implausible
// message and goes on (docs/user/lcm.md, "Time faults"; docs/user/messages.md, "Plausibility").
#include <CLI/CLI.hpp>

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/cli.h"
#include "omnislam/lcmio/decode.h"
#include "omnislam/lcmio/signals.h"

using namespace omnislam;

namespace {

struct Alteration {
  double utime_offset_s = 0.0;
  std::map<std::string, double> fields;  ///< field name -> value (set --set)
};

/// The message's type from its channel name (the contract's, docs/user/messages.md), or --type.
std::string typeOfChannel(const std::string& channel) {
  if (channel == channels::kOmniImage) return "image";
  if (channel == channels::kOmniFeatures) return "features";
  if (channel == channels::kOdometry) return "odometry";
  if (channel == channels::kGroundTruthPose || channel == channels::kSlamPose) return "pose";
  return "";
}

std::string num(double v) {
  std::ostringstream o;
  o.precision(17);
  o << v;
  return o.str();
}

/// Sets a planar pose's field by name; false if the name is not one of it.
template <class Msg>
bool setPoseField(Msg& m, const std::string& name, double v) {
  if (name == "x" || name == "x_m") m.x_m = v;
  else if (name == "y" || name == "y_m") m.y_m = v;
  else if (name == "theta" || name == "theta_rad") m.theta_rad = v;
  else return false;
  return true;
}
bool setField(pose_t& m, const std::string& n, double v) { return setPoseField(m, n, v); }
bool setField(odometry_t& m, const std::string& n, double v) {
  if (n == "v" || n == "v_mps") return m.v_mps = v, true;
  if (n == "omega" || n == "omega_radps") return m.omega_radps = v, true;
  return setPoseField(m, n, v);
}
bool setField(image_t&, const std::string&, double) { return false; }
bool setField(features_t& m, const std::string& n, double v) {
  if (n == "camera_z" || n == "camera_z_m") return m.camera_position_m[2] = v, true;
  return false;
}

struct Capture {
  std::string channel;
  int skip = 0;
  int seen = 0;
  std::optional<std::vector<uint8_t>> bytes;
};

void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string&, Capture* c) {
  if (c->bytes || c->seen++ < c->skip) return;
  const auto* p = static_cast<const uint8_t*>(rbuf->data);
  c->bytes = std::vector<uint8_t>(p, p + rbuf->data_size);
}

/// Decodes, alters, publishes; the one line printed says what was sent.
template <class Msg>
int alterAndPublish(lcm::LCM& lcm, const Capture& c, const Alteration& a) {
  Msg m;
  if (auto why = lcmio::decode(c.bytes->data(), c.bytes->size(), m)) {
    std::cerr << "omnislam-inject: the message on " << c.channel << " does not decode as " << Msg::getTypeName() << ": "
              << *why << std::endl;
    return app::kFailure;
  }
  const int64_t original = m.utime;
  m.utime = original + static_cast<int64_t>(std::llround(a.utime_offset_s * 1e6));
  std::string set;
  for (const auto& [name, v] : a.fields) {
    if (!setField(m, name, v)) {
      std::cerr << "omnislam-inject: --set " << name << ": " << Msg::getTypeName() << " has no such field "
                << "(pose: x, y, theta; odometry: also v, omega; features: camera_z)" << std::endl;
      return app::kBadConfig;
    }
    set += " " + name + "=" + num(v);
  }
  if (lcm.publish(c.channel, &m) != 0) {
    std::cerr << "omnislam-inject: publishing on " << c.channel << " failed" << std::endl;
    return app::kFailure;
  }
  std::cout << "sent " << c.channel << " seq " << m.seq << " utime " << m.utime << " (original " << original << ", "
            << (a.utime_offset_s >= 0 ? "+" : "") << num(a.utime_offset_s) << " s)" << set << std::endl;
  return app::kOk;
}

std::map<std::string, double> parseSets(const std::vector<std::string>& sets) {
  std::map<std::string, double> out;
  for (const std::string& s : sets) {
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0) throw std::invalid_argument("--set '" + s + "': expected FIELD=VALUE");
    const std::string v = s.substr(eq + 1);
    char* end = nullptr;
    const double d = std::strtod(v.c_str(), &end);  // takes nan, inf, 1e300
    if (v.empty() || end != v.c_str() + v.size())
      throw std::invalid_argument("--set '" + s + "': VALUE is not a number");
    out[s.substr(0, eq)] = d;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-inject: alters the next real message of a channel and publishes it once (fault injection)"};
  std::string channel, type, url;
  std::vector<std::string> sets;
  Alteration alt;
  bool offset_given = false;
  Capture cap;
  double timeout_s = 30.0;
  cli.add_option("--channel", channel, "channel to take the message from and publish it on")->required();
  cli.add_option("--type", type, "image | features | odometry | pose (default: from the channel name)")
      ->check(CLI::IsMember({"image", "features", "odometry", "pose"}));
  CLI::Option* offset =
      cli.add_option("--utime-offset-s", alt.utime_offset_s, "shift of the utime in seconds (e.g. 100, 1e6, -30)")
          ->check(app::FiniteRange(-1e9, 1e9));
  cli.add_option("--set", sets,
                 "FIELD=VALUE, repeatable: x, y, theta (pose, odometry), v, omega (odometry), camera_z "
                 "(features); VALUE may be nan, inf, 1e300. Without --utime-offset-s the utime is "
                 "moved 1 us ahead, so that it is no duplicate of the original");
  cli.add_option("--skip", cap.skip, "real messages to let pass before the one taken")->check(CLI::Range(0, 100000000));
  cli.add_option("--timeout-s", timeout_s, "give up after this many seconds without the message (exit 1)")
      ->check(app::FiniteRange(0.1, 86400.0));
  cli.add_option("--url", url, "LCM URL (default: $LCM_DEFAULT_URL)");
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  offset_given = offset->count() > 0;
  return app::runMain("omnislam-inject", [&]() -> int {
    if (type.empty()) type = typeOfChannel(channel);
    if (type.empty())
      throw std::invalid_argument("--type: channel '" + channel +
                                  "' is not one of the contract's pose, "
                                  "odometry, image or features channels; name its type");
    alt.fields = parseSets(sets);
    if (!alt.fields.empty() && !offset_given) alt.utime_offset_s = 1e-6;
    lcm::LCM lcm(app::lcmUrl(url));
    if (!lcm.good()) throw std::runtime_error("cannot start LCM (check the URL and multicast routing)");
    lcmio::installStopHandlers();
    cap.channel = channel;
    lcm.subscribeFunction(channel, &onMessage, &cap);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!cap.bytes && !lcmio::stopRequested() && std::chrono::steady_clock::now() < deadline) lcm.handleTimeout(50);
    if (!cap.bytes) {
      std::cerr << "omnislam-inject: no message on " << channel << " within " << timeout_s << " s (" << cap.seen
                << " seen, --skip " << cap.skip << ")" << std::endl;
      return app::kFailure;
    }
    if (type == "image") return alterAndPublish<image_t>(lcm, cap, alt);
    if (type == "features") return alterAndPublish<features_t>(lcm, cap, alt);
    if (type == "odometry") return alterAndPublish<odometry_t>(lcm, cap, alt);
    return alterAndPublish<pose_t>(lcm, cap, alt);
  });
}
