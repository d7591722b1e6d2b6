// Writing LCM log files (the lcm-logger format) event by event: raw bytes or an encoded message,
// with the event number counted and every write checked. The counterpart of log_reader.h.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace omnislam::lcmio {

class LogWriter {
 public:
  /// How the file appears. kDirect: written in place (a stop part-way leaves the events so far,
  /// which is what a replay interrupted on purpose keeps). kAtomic: written to PATH.partial and
  /// renamed to PATH by commit(), so a run killed part-way never leaves a short file that reads as
  /// complete; without commit() the .partial file is all there is.
  enum class Mode { kDirect, kAtomic };
  /// Creates (truncates) the file; throws std::runtime_error naming it when it cannot be written.
  explicit LogWriter(const std::string& path, Mode mode = Mode::kDirect);
  ~LogWriter();  // closes the file unchecked (kAtomic: without renaming it): call commit()
  /// Flushes and syncs the file, closes it and (kAtomic) renames it to the path; throws
  /// std::runtime_error when any of it fails (a full disk shows here: stdio writes the last
  /// buffer only now, and the destructor's close cannot report). No write after it.
  void commit();
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  /// One event with the given log timestamp (microseconds); throws std::runtime_error on failure.
  /// Events wait in a buffer of kBufferBytes and go to the file together, so a write that fails
  /// (a full disk) may be the one of a later event, or commit()'s. After a failure every later
  /// write throws without writing (the failed one may have left a torn event, where readers stop),
  /// and commit() throws after closing the file (kAtomic: not renamed).
  void write(int64_t timestamp, const std::string& channel, const void* data, int32_t size);
  template <class Msg>
  void write(int64_t timestamp, const std::string& channel, const Msg& m) {
    std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
    m.encode(buf.data(), 0, static_cast<int>(buf.size()));
    write(timestamp, channel, buf.data(), static_cast<int32_t>(buf.size()));
  }
  /// Events written: every event write() took (the last ones may still wait in the buffer, for a
  /// later write or commit()); after a failure, only those complete in the file.
  int64_t events() const { return failed_ ? in_file_ : n_; }
  /// Events write() took without an error that a later failure kept out of the file (they were
  /// still in the buffer, or torn by the failed write); 0 without a failure.
  int64_t lost() const { return failed_ ? n_ - in_file_ : 0; }
  /// Bytes of the events() events in the log format (headers included): what the file holds, or
  /// will once the buffer is written; after a failure, only the complete events' bytes.
  int64_t bytes() const { return failed_ ? bytes_in_file_ : bytes_in_file_ + static_cast<int64_t>(buf_.size()); }
  const std::string& path() const { return path_; }
  /// The system's reason for the first failed write (e.g. "No space left on device"); empty before.
  const std::string& failure() const { return failure_; }
  /// Writes the buffered events to the file now (to the operating system, not synced to the
  /// disk), so that a crash or SIGKILL of this process cannot lose them: a recorder calls it now
  /// and then. Throws std::runtime_error as write() does when the write fails (the events it did
  /// not complete are then lost(), as on write()'s failure); does nothing after an earlier failure
  /// (already reported by the write that failed) or when nothing is buffered. Not after commit().
  void flushBuffered();

  static constexpr size_t kBufferBytes = 32 * 1024;

 private:
  bool flush();  // writes the buffer; false (failed_, the events counted) on an error

  std::string path_;
  Mode mode_;
  int fd_ = -1;
  std::vector<uint8_t> buf_;   // events not yet in the file
  std::vector<size_t> ends_;   // where each of them ends in buf_
  int64_t n_ = 0;              // events taken (the next event number)
  int64_t in_file_ = 0;        // events known complete in the file
  int64_t bytes_in_file_ = 0;  // their bytes
  bool failed_ = false;
  std::string failure_;  // the system's reason for the first failure (strerror), for the messages
};

/// Checked at start, before any work whose result would go there: throws std::invalid_argument
/// ("FLAG: cannot write 'PATH': REASON") when `path` is a folder, or a file cannot be created in
/// its folder (missing folder, no permission, read-only file system: probed by creating and
/// removing a file beside it, since root's access() says yes to read-only mounts and /proc).
void requireWritableFile(const std::string& path, const std::string& flag);

}  // namespace omnislam::lcmio
