// LCM log writing: see log_writer.h.
//
// The events are written here, not through lcm::LogFile, so that the count stays honest when the
// disk fills up: stdio takes an event into its buffer and says nothing about whether it ever reaches
// the file, so a failure loses the buffered events while they count as written (through stdio, a full
// disk reported 714 events for 687 in the file; /dev/full reported 27 for none). Here the buffer is ours
// and write(2) says how many bytes reached the file, so an event counts once it is complete there.
// Flushing stdio after every event would have kept lcm::LogFile, but costs a system call per event:
// 500 000 events of 200 bytes took 2.3-7.8 us each flushed, 0.4-1.6 us buffered by stdio (a
// 2-core machine, quiet to loaded), which a recorder on a flooded bus cannot afford. This writer
// took 0.41-0.46 us with its 32 KiB buffer (0.6 us with 8 KiB). The format is
// lcm_eventlog_write_event's.
#include "omnislam/lcmio/log_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <filesystem>
#include <cstring>

namespace omnislam::lcmio {

namespace {
std::string fileOf(const std::string& path, LogWriter::Mode mode) {
  return mode == LogWriter::Mode::kAtomic ? path + ".partial" : path;
}

constexpr uint32_t kSyncWord = 0xEDA1DA01;

void putBigEndian(std::vector<uint8_t>& buf, uint64_t v, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) buf.push_back(static_cast<uint8_t>(v >> (8 * i)));
}
}  // namespace

LogWriter::LogWriter(const std::string& path, Mode mode) : path_(path), mode_(mode) {
  fd_ = ::open(fileOf(path, mode).c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd_ < 0) throw std::runtime_error("cannot write LCM log '" + fileOf(path, mode) + "': " + std::strerror(errno));
  buf_.reserve(kBufferBytes);
}

LogWriter::~LogWriter() {
  if (fd_ < 0) return;
  if (!failed_) flush();  // unchecked, as a close; commit() is the checked way
  ::close(fd_);
}

bool LogWriter::flush() {
  size_t done = 0;
  while (done < buf_.size()) {
    const ssize_t w = ::write(fd_, buf_.data() + done, buf_.size() - done);
    if (w < 0 && errno == EINTR) continue;
    if (w < 0) failure_ = std::strerror(errno);
    if (w == 0) failure_ = "the system wrote nothing";
    if (w <= 0) break;
    done += static_cast<size_t>(w);
  }
  // The events that ended within what was written are complete in the file; a torn one is not.
  const auto complete = std::upper_bound(ends_.begin(), ends_.end(), done) - ends_.begin();
  in_file_ += complete;
  bytes_in_file_ += complete > 0 ? static_cast<int64_t>(ends_[static_cast<size_t>(complete) - 1]) : 0;
  const bool ok = done == buf_.size();
  if (!ok) failed_ = true;
  buf_.clear();
  ends_.clear();
  return ok;
}

void LogWriter::flushBuffered() {
  if (fd_ < 0) throw std::runtime_error("LCM log '" + path_ + "' flushed after commit()");
  if (failed_ || buf_.empty()) return;
  if (!flush()) throw std::runtime_error("writing LCM log '" + path_ + "' failed: " + failure_);
}

void LogWriter::commit() {
  if (fd_ < 0) throw std::runtime_error("LCM log '" + path_ + "' committed twice");
  const bool was_failed = failed_;
  // fsync fails with EINVAL on a pipe or a device (--out /dev/stdout): nothing to sync there.
  const bool flushed = (failed_ || flush()) && (fsync(fd_) == 0 || errno == EINVAL);
  if (!flushed && !was_failed && failure_.empty()) failure_ = std::string("fsync: ") + std::strerror(errno);
  const bool closed = ::close(fd_) == 0;
  if (!closed && failure_.empty()) failure_ = std::string("close: ") + std::strerror(errno);
  fd_ = -1;
  if (was_failed)  // kAtomic: not renamed, so a log that stops short never takes the final name
    throw std::runtime_error("writing LCM log '" + fileOf(path_, mode_) + "' failed (" + failure_ +
                             "): it ends at the failed write");
  if (!flushed || !closed)
    throw std::runtime_error("writing LCM log '" + fileOf(path_, mode_) + "' failed (flush): " + failure_);
  if (mode_ == Mode::kAtomic && std::rename(fileOf(path_, mode_).c_str(), path_.c_str()) != 0)
    throw std::runtime_error("cannot rename '" + fileOf(path_, mode_) + "' to '" + path_ + "'");
}

void LogWriter::write(int64_t timestamp, const std::string& channel, const void* data, int32_t size) {
  if (fd_ < 0) throw std::runtime_error("LCM log '" + path_ + "' written after commit()");
  // A failed write can leave a torn event, and the log readers stop there. Writing on after it
  // would add events nobody can read.
  if (failed_) throw std::runtime_error("LCM log '" + path_ + "' not written: an earlier write failed");
  if (size < 0) throw std::invalid_argument("LCM log '" + path_ + "': negative data size");
  putBigEndian(buf_, kSyncWord, 4);
  putBigEndian(buf_, static_cast<uint64_t>(n_), 8);
  putBigEndian(buf_, static_cast<uint64_t>(timestamp), 8);
  putBigEndian(buf_, channel.size(), 4);
  putBigEndian(buf_, static_cast<uint32_t>(size), 4);
  buf_.insert(buf_.end(), channel.begin(), channel.end());
  const auto* bytes = static_cast<const uint8_t*>(data);
  buf_.insert(buf_.end(), bytes, bytes + size);
  ends_.push_back(buf_.size());
  ++n_;
  if (buf_.size() >= kBufferBytes && !flush()) {
    --n_;  // this event is the last in the buffer, so not complete in the file: it is not taken
    throw std::runtime_error("writing LCM log '" + path_ + "' failed: " + failure_);
  }
}

void requireWritableFile(const std::string& path, const std::string& flag) {
  namespace fs = std::filesystem;
  auto refuse = [&](const std::string& why) {
    throw std::invalid_argument(flag + ": cannot write '" + path + "': " + why);
  };
  if (path.empty()) refuse("no path given");
  std::error_code ec;
  if (fs::is_directory(path, ec)) refuse("it is a folder");
  const fs::path dir = fs::path(path).has_parent_path() ? fs::path(path).parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec)) refuse("its folder '" + dir.string() + "' does not exist");
  const fs::path probe = dir / (".omnislam-write-probe-" + std::to_string(::getpid()));
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) refuse(std::string("cannot create a file in '") + dir.string() + "': " + std::strerror(errno));
  ::close(fd);
  ::unlink(probe.c_str());
}

}  // namespace omnislam::lcmio
