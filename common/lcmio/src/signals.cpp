// SIGINT / SIGTERM flag: see signals.h.
#include "omnislam/lcmio/signals.h"

#include <atomic>
#include <csignal>

namespace omnislam::lcmio {
namespace {
std::atomic<int> g_stop_signal{0};
std::atomic<bool> g_stop{false};
std::atomic<int> g_stop_signals{0};
extern "C" void onSignal(int sig) {
  g_stop_signals.fetch_add(1);
  g_stop_signal.store(sig);
  g_stop.store(true);
}
}  // namespace

void installStopHandlers() {
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: blocking calls return EINTR so loops notice promptly
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

bool stopRequested() { return g_stop.load(); }
void requestStop() { g_stop.store(true); }
int stopSignal() { return g_stop_signal.load(); }
int stopSignalCount() { return g_stop_signals.load(); }

}  // namespace omnislam::lcmio
