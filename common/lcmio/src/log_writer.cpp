// LCM log writing: see log_writer.h.
#include "omnislam/lcmio/log_writer.h"

#include <lcm/lcm-cpp.hpp>

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <stdexcept>

namespace omnislam::lcmio {

namespace {
std::string fileOf(const std::string& path, LogWriter::Mode mode) {
  return mode == LogWriter::Mode::kAtomic ? path + ".partial" : path;
}
}  // namespace

LogWriter::LogWriter(const std::string& path, Mode mode)
    : path_(path), mode_(mode), log_(std::make_unique<lcm::LogFile>(fileOf(path, mode), "w")) {
  if (!log_->good()) throw std::runtime_error("cannot write LCM log '" + fileOf(path, mode) + "'");
}

LogWriter::~LogWriter() = default;

void LogWriter::commit() {
  if (!log_) throw std::runtime_error("LCM log '" + path_ + "' committed twice");
  std::FILE* f = log_->getFilePtr();
  // fsync fails with EINVAL on a pipe or a device (--out /dev/stdout): nothing to sync there.
  const bool flushed = f && std::fflush(f) == 0 && (fsync(fileno(f)) == 0 || errno == EINVAL);
  log_.reset();  // closes
  if (!flushed) throw std::runtime_error("writing LCM log '" + fileOf(path_, mode_) + "' failed (flush)");
  if (failed_)  // kAtomic: not renamed, so a log that stops short never takes the final name
    throw std::runtime_error("writing LCM log '" + fileOf(path_, mode_) + "' failed: it ends at the failed write");
  if (mode_ == Mode::kAtomic && std::rename(fileOf(path_, mode_).c_str(), path_.c_str()) != 0)
    throw std::runtime_error("cannot rename '" + fileOf(path_, mode_) + "' to '" + path_ + "'");
}

void LogWriter::write(int64_t timestamp, const std::string& channel, const void* data, int32_t size) {
  lcm::LogEvent ev;
  ev.eventnum = n_;
  ev.timestamp = timestamp;
  ev.channel = channel;
  ev.datalen = size;
  ev.data = const_cast<void*>(data);
  if (!log_) throw std::runtime_error("LCM log '" + path_ + "' written after commit()");
  // LCM writes header, channel and data separately: a failure can leave a torn event, and the
  // log readers stop there. Writing on after it would add events nobody can read.
  if (failed_) throw std::runtime_error("LCM log '" + path_ + "' not written: an earlier write failed");
  if (log_->writeEvent(&ev) != 0) {
    failed_ = true;
    throw std::runtime_error("writing LCM log '" + path_ + "' failed");
  }
  ++n_;
}

}  // namespace omnislam::lcmio
