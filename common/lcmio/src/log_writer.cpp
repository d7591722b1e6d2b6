// LCM log writing: see log_writer.h.
#include "omnislam/lcmio/log_writer.h"

#include <lcm/lcm-cpp.hpp>

#include <stdexcept>

namespace omnislam::lcmio {

LogWriter::LogWriter(const std::string& path) : path_(path), log_(std::make_unique<lcm::LogFile>(path, "w")) {
  if (!log_->good()) throw std::runtime_error("cannot write LCM log '" + path + "'");
}

LogWriter::~LogWriter() = default;

void LogWriter::write(int64_t timestamp, const std::string& channel, const void* data, int32_t size) {
  lcm::LogEvent ev;
  ev.eventnum = n_++;
  ev.timestamp = timestamp;
  ev.channel = channel;
  ev.datalen = size;
  ev.data = const_cast<void*>(data);
  if (log_->writeEvent(&ev) != 0) throw std::runtime_error("writing LCM log '" + path_ + "' failed");
}

}  // namespace omnislam::lcmio
