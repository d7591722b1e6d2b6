// LCM log reading: see log_reader.h.
#include "omnislam/lcmio/log_reader.h"

#include <lcm/lcm-cpp.hpp>

#include <stdexcept>

namespace omnislam::lcmio {

void forEachEvent(const std::string& path, const std::function<void(const LogEvent&)>& fn) {
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error("cannot open LCM log '" + path + "'");
  LogEvent out;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    out.event_number = ev->eventnum;
    out.log_utime = ev->timestamp;
    out.channel = ev->channel;
    const auto* p = static_cast<const uint8_t*>(ev->data);
    out.data.assign(p, p + ev->datalen);
    fn(out);
  }
}

}  // namespace omnislam::lcmio
