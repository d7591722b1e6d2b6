// Test support: two network namespaces joined by a veth pair, as two hosts on one link, for tests of
// LCM multicast across machines. Names, addresses, multicast group and port come from the pid (so
// parallel tests never meet); everything is torn down by the destructor, also after a failure: the
// processes still running in either namespace are killed, then the namespaces (and with them the
// veth pair) are deleted. Needs `ip` (iproute2) and root or CAP_NET_ADMIN + CAP_SYS_ADMIN;
// unavailable() says why not, for GTEST_SKIP.
#pragma once

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "proc_util.h"

namespace omnislam::testing {

class NetnsPair {
 public:
  /// Creates both namespaces, the veth pair (one end in each, addresses in a private /30, multicast
  /// on, up), lo up and a route for 224.0.0.0/4 on the veth end in each. On failure error() names
  /// the command and its output, and what was made is removed again.
  NetnsPair() {
    const int pid = static_cast<int>(getpid());
    ns_[0] = "osnA" + std::to_string(pid), ns_[1] = "osnB" + std::to_string(pid);  // <= 11 chars
    veth_[0] = "osv" + std::to_string(pid) + "a", veth_[1] = "osv" + std::to_string(pid) + "b";
    const int block = pid % 16384;  // a /30 of 10.213.0.0/16
    const std::string net = "10.213." + std::to_string(block / 64) + ".";
    addr_[0] = net + std::to_string((block % 64) * 4 + 1), addr_[1] = net + std::to_string((block % 64) * 4 + 2);
    group_ = "239.255." + std::to_string(100 + (pid / 256) % 100) + "." + std::to_string(pid % 256);
    port_ = 20000 + pid % 30000;
    removeStale();
    if (!ip({"netns", "add", ns_[0]})) return;
    made_ = true;
    if (!ip({"netns", "add", ns_[1]}) || !ip({"link", "add", veth_[0], "type", "veth", "peer", "name", veth_[1]}))
      return;
    for (int k = 0; k < 2; ++k)
      if (!ip({"link", "set", veth_[k], "netns", ns_[k]}) ||
          !ip({"-n", ns_[k], "addr", "add", addr_[k] + "/30", "dev", veth_[k]}) ||
          !ip({"-n", ns_[k], "link", "set", "lo", "up"}) ||
          !ip({"-n", ns_[k], "link", "set", veth_[k], "multicast", "on"}) ||
          !ip({"-n", ns_[k], "link", "set", veth_[k], "up"}) ||
          !ip({"-n", ns_[k], "route", "add", "224.0.0.0/4", "dev", veth_[k]}))
        return;
  }
  ~NetnsPair() { tearDown(); }
  NetnsPair(const NetnsPair&) = delete;
  NetnsPair& operator=(const NetnsPair&) = delete;

  /// "" when `ip` is there and namespaces can be made here, else why not (a skip message).
  static std::string unavailable() {
    const RunResult v = run({"ip", "-V"}, 10);
    if (v.exit_code != 0) return "no usable `ip` (iproute2) on the PATH: " + v.output;
    if (!hasCapability(12)) return "needs root or CAP_NET_ADMIN to make network namespaces (CapEff lacks bit 12)";
    return "";
  }
  const std::string& error() const { return error_; }
  const std::string& ns(int k) const { return ns_[k]; }
  const std::string& address(int k) const { return addr_[k]; }
  /// The private LCM URL of the pair: the pid's group and port, ttl as given, a 4 MB receive buffer.
  std::string url(int ttl) const {
    return "udpm://" + group_ + ":" + std::to_string(port_) + "?ttl=" + std::to_string(ttl) + "&recv_buf_size=4194304";
  }
  /// argv run inside namespace k: ip netns exec NS argv...
  std::vector<std::string> in(int k, const std::vector<std::string>& argv) const {
    std::vector<std::string> out{"ip", "netns", "exec", ns_[k]};
    out.insert(out.end(), argv.begin(), argv.end());
    return out;
  }
  /// Kills what still runs in the namespaces and deletes them (the veth pair goes with them).
  void tearDown() {
    if (!made_) return;
    for (int round = 0; round < 2; ++round)
      for (const auto& n : ns_)
        for (pid_t p : pidsIn(n)) kill(p, SIGKILL);
    for (const auto& n : ns_) run({"ip", "netns", "del", n}, 10);
    run({"ip", "link", "del", veth_[0]}, 10);  // left in this namespace if moving it failed (else gone)
    made_ = false;
  }

 private:
  bool ip(const std::vector<std::string>& args) {
    std::vector<std::string> argv{"ip"};
    argv.insert(argv.end(), args.begin(), args.end());
    const RunResult r = run(argv, 10);
    if (r.exit_code == 0) return true;
    std::string cmd;
    for (const auto& a : argv) cmd += (cmd.empty() ? "" : " ") + a;
    error_ = "`" + cmd + "` failed (exit code " + std::to_string(r.exit_code) + "): " + r.output;
    tearDown();
    return false;
  }
  static std::vector<pid_t> pidsIn(const std::string& ns) {
    std::vector<pid_t> pids;
    std::istringstream in(run({"ip", "netns", "pids", ns}, 10).output);
    for (long p; in >> p;)
      if (p > 1) pids.push_back(static_cast<pid_t>(p));
    return pids;
  }
  /// Namespaces of this naming left by a test that was itself killed (SIGKILL, a timeout), whose
  /// pid is gone: what still runs in them (that test's processes: a launcher there runs until
  /// SIGINT) is killed and they are deleted, so that neither piles up.
  static void removeStale() {
    std::istringstream in(run({"ip", "netns", "list"}, 10).output);
    const std::regex mine("^(osn[AB]([0-9]+))\\b.*");
    std::smatch m;
    for (std::string line; std::getline(in, line);) {
      if (!std::regex_match(line, m, mine) || kill(std::stoi(m[2]), 0) == 0 || errno != ESRCH) continue;
      for (pid_t p : pidsIn(m[1])) kill(p, SIGKILL);
      run({"ip", "netns", "del", m[1]}, 10);
    }
  }
  static bool hasCapability(int bit) {
    std::ifstream f("/proc/self/status");
    for (std::string line; std::getline(f, line);)
      if (line.rfind("CapEff:", 0) == 0) return (std::stoull(line.substr(7), nullptr, 16) >> bit) & 1ULL;
    return geteuid() == 0;
  }
  std::string ns_[2], veth_[2], addr_[2], group_, error_;
  int port_ = 0;
  bool made_ = false;
};

}  // namespace omnislam::testing
