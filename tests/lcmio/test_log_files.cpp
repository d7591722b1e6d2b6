// Log files: a truncated or corrupt tail is told apart from the end of the log and named; a log
// through a pipe is read whole; an atomic writer leaves PATH.partial until commit(); after a failed
// write nothing more is written, and the events counted written are those in the file; an output
// that is the input is refused.
#include <gtest/gtest.h>

#include <stdlib.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/odometry_t.hpp"
#include "log_bytes.h"

using namespace omnislam;
using omnislam::testing::rawLogEvent;
namespace fs = std::filesystem;

namespace {

struct Dir {
  std::string path;
  Dir() {
    char tmpl[] = "/tmp/omnislam-logfiles-XXXXXX";
    path = mkdtemp(tmpl);
  }
  ~Dir() { fs::remove_all(path); }
  std::string file(const std::string& n) const { return path + "/" + n; }
};

void writeOdometry(lcmio::LogWriter& w, int n) {
  for (int k = 0; k < n; ++k) {
    odometry_t m{};
    m.utime = 1'000'000 + k * 20'000;
    m.seq = k;
    w.write(m.utime, "ODOMETRY", m);
  }
}

int64_t count(const std::string& path, lcmio::LogReadResult* result = nullptr) {
  int64_t n = 0;
  const auto r = lcmio::forEachEvent(path, [&](const lcmio::LogEvent&) { ++n; });
  if (result) *result = r;
  return n;
}

// LogWriter writes LCM's event log format itself (so that a failure's count is honest): LCM's own
// reader (lcm::LogFile, what lcm-logplayer and the file:// provider use) must read back every event
// as written, in a log big enough to go through the writer's buffer several times, with events of
// several sizes, an empty one, and one larger than the buffer.
TEST(LogFiles, LcmsOwnReaderReadsWhatLogWriterWrites) {
  Dir d;
  const std::string path = d.file("compat.lcm");
  std::vector<std::pair<std::string, std::vector<uint8_t>>> written;
  {
    lcmio::LogWriter w(path, lcmio::LogWriter::Mode::kDirect);
    for (int k = 0; k < 3000; ++k) {
      const size_t size = k == 7 ? 0 : k == 1500 ? 100'000 : static_cast<size_t>((k * 37) % 700);
      std::vector<uint8_t> data(size);
      for (size_t i = 0; i < size; ++i) data[i] = static_cast<uint8_t>(k + i);
      const std::string channel = k % 3 == 0 ? "ODOMETRY" : "OMNI_FEATURES_" + std::to_string(k % 5);
      w.write(1'000'000 + k, channel, data.data(), static_cast<int32_t>(data.size()));
      written.emplace_back(channel, std::move(data));
    }
    w.commit();
  }
  lcm::LogFile log(path, "r");
  ASSERT_TRUE(log.good());
  size_t k = 0;
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent(), ++k) {
    ASSERT_LT(k, written.size());
    EXPECT_EQ(ev->eventnum, static_cast<int64_t>(k));
    EXPECT_EQ(ev->timestamp, 1'000'000 + static_cast<int64_t>(k));
    EXPECT_EQ(ev->channel, written[k].first);
    ASSERT_EQ(ev->datalen, static_cast<int32_t>(written[k].second.size())) << k;
    if (ev->datalen > 0) {  // (memcmp with an empty event's null pointers is undefined)
      EXPECT_EQ(0, std::memcmp(ev->data, written[k].second.data(), written[k].second.size())) << k;
    }
  }
  EXPECT_EQ(k, written.size());
}

TEST(LogFiles, ATruncatedOrCorruptTailIsNamedNotTakenForTheEnd) {
  Dir d;
  {
    lcmio::LogWriter w(d.file("full.lcm"));
    writeOdometry(w, 100);
  }
  lcmio::LogReadResult full;
  ASSERT_EQ(count(d.file("full.lcm"), &full), 100);
  EXPECT_EQ(full.unreadable(), 0);
  EXPECT_FALSE(full.problem("full.lcm"));
  // Cut in the middle of an event (a logger killed while writing).
  const auto size = fs::file_size(d.file("full.lcm"));
  fs::copy_file(d.file("full.lcm"), d.file("cut.lcm"));
  fs::resize_file(d.file("cut.lcm"), size - 50);
  lcmio::LogReadResult cut;
  EXPECT_EQ(count(d.file("cut.lcm"), &cut), 99) << "each event is 100 bytes: the last one is cut";
  EXPECT_EQ(cut.file_bytes, static_cast<int64_t>(size - 50));
  EXPECT_GT(cut.unreadable(), 0);
  ASSERT_TRUE(cut.problem("cut.lcm"));
  EXPECT_NE(cut.problem("cut.lcm")->find("cut.lcm: "), std::string::npos);
  EXPECT_NE(cut.problem("cut.lcm")->find("the 50 bytes after its first 99 events (from byte 9900 of 9950)"),
            std::string::npos)
      << *cut.problem("cut.lcm");
  // A damaged sync word in the middle: the events after it are not read, and that is said.
  fs::copy_file(d.file("full.lcm"), d.file("junk.lcm"));
  {
    std::fstream f(d.file("junk.lcm"), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(size / 2));
    const char zeros[64] = {};
    f.write(zeros, sizeof zeros);
  }
  lcmio::LogReadResult junk;
  const int64_t read = count(d.file("junk.lcm"), &junk);
  EXPECT_LT(read, 100);
  EXPECT_GT(junk.unreadable(), static_cast<int64_t>(size / 3)) << "the rest of the file is reported";
  EXPECT_TRUE(junk.problem("junk.lcm"));
}

void writeBytes(const std::string& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

// LCM 1.3.1's reader allocates data length + 1 bytes unchecked: 2^31 - 1 overflows, and it reads
// into a null pointer on this 72-byte file. Our reader (logstat, eval, viewer --log and slam
// --replay read with it) checks every length against the file first.
TEST(LogFiles, LengthsThatRunPastTheFileStopReadingWithAReason) {
  Dir d;
  writeBytes(d.file("huge.lcm"), rawLogEvent(0, "A", "good") + rawLogEvent(1, "A", "0123456789", 0x7fffffff));
  lcmio::LogReadResult huge;
  EXPECT_EQ(count(d.file("huge.lcm"), &huge), 1);
  EXPECT_EQ(huge.file_bytes, 72);
  EXPECT_EQ(huge.bytes_read, 33);
  ASSERT_TRUE(huge.problem("huge.lcm"));
  EXPECT_NE(huge.problem("huge.lcm")->find("data length 2147483647 at byte 33 runs past the end of the file"),
            std::string::npos)
      << *huge.problem("huge.lcm");
  for (const int64_t bad_channel : {int64_t{0}, int64_t{1000}, int64_t{0xffffffff}}) {
    writeBytes(d.file("ch.lcm"), rawLogEvent(0, "A", "good") + rawLogEvent(1, "A", "x", -1, bad_channel));
    lcmio::LogReadResult ch;
    EXPECT_EQ(count(d.file("ch.lcm"), &ch), 1) << bad_channel;
    ASSERT_TRUE(ch.problem("ch.lcm"));
    EXPECT_NE(ch.problem("ch.lcm")->find("outside 1..999"), std::string::npos) << *ch.problem("ch.lcm");
  }
  // A data length one byte too long: the event is not followed by a sync word, so it is not used.
  writeBytes(d.file("long.lcm"), rawLogEvent(0, "A", "good", 5) + rawLogEvent(1, "A", "next"));
  lcmio::LogReadResult lng;
  EXPECT_EQ(count(d.file("long.lcm"), &lng), 0);
  ASSERT_TRUE(lng.problem("long.lcm"));
  EXPECT_NE(lng.problem("long.lcm")->find("not followed by another event"), std::string::npos)
      << *lng.problem("long.lcm");
}

// A data length that covers the next two events exactly and ends at a third's header: the two
// vanished inside it without a word. The event numbers show it.
TEST(LogFiles, EventsSwallowedByACorruptLengthAreCountedByTheirNumbers) {
  Dir d;
  const std::string e1 = rawLogEvent(1, "A", "one"), e2 = rawLogEvent(2, "A", "two");
  writeBytes(d.file("swallow.lcm"),
             rawLogEvent(0, "A", "zero" + e1 + e2, 4 + static_cast<int64_t>(e1.size() + e2.size())) +
                 rawLogEvent(3, "A", "three"));
  std::vector<int64_t> numbers;
  const auto r =
      lcmio::forEachEvent(d.file("swallow.lcm"), [&](const lcmio::LogEvent& e) { numbers.push_back(e.event_number); });
  EXPECT_EQ(numbers, (std::vector<int64_t>{0, 3}));
  EXPECT_EQ(r.missing_event_numbers, 2);
  EXPECT_EQ(r.unreadable(), 0);
  ASSERT_TRUE(r.problem("swallow.lcm"));
  EXPECT_NE(r.problem("swallow.lcm")->find("2 event numbers are missing"), std::string::npos)
      << *r.problem("swallow.lcm");
  // Corrupted numbers far apart or negative: counted without overflow, every event still read.
  const int64_t most = std::numeric_limits<int64_t>::max();
  writeBytes(d.file("numbers.lcm"), rawLogEvent(most, "A", "a") + rawLogEvent(-5, "A", "b") + rawLogEvent(0, "A", "c") +
                                        rawLogEvent(most, "A", "d"));
  const auto n = lcmio::forEachEvent(d.file("numbers.lcm"), [](const lcmio::LogEvent&) {});
  EXPECT_EQ(n.events, 4);
  EXPECT_EQ(n.missing_event_numbers, std::numeric_limits<int64_t>::max() - 1);
}

// Reads through a FIFO: `bytes` written by a thread into a named pipe that the reader reads, as
// `omnislam-logstat <(zcat log.lcm.gz)` would.
lcmio::LogReadResult readThroughPipe(const Dir& d, const std::string& bytes, int64_t* events) {
  const std::string fifo = d.file("pipe");
  if (mkfifo(fifo.c_str(), 0600) != 0) throw std::runtime_error("mkfifo failed");
  std::thread writer([&] { std::ofstream(fifo, std::ios::binary) << bytes; });
  int64_t n = 0;
  const auto r = lcmio::forEachEvent(fifo, [&](const lcmio::LogEvent&) { ++n; });
  writer.join();
  fs::remove(fifo);
  *events = n;
  return r;
}

// A pipe cannot seek back: the reader checks the next event's sync word without seeking, so a log
// of two or more events is read whole through a pipe. And a corrupt length from a pipe, where no
// file size bounds it, must not allocate the length at once.
TEST(LogFiles, APipeIsReadWholeAndACorruptLengthThroughItCostsLittleMemory) {
  Dir d;
  const std::string log = rawLogEvent(0, "A", "zero") + rawLogEvent(1, "BB", "") + rawLogEvent(2, "A", "two");
  int64_t events = 0;
  lcmio::LogReadResult r = readThroughPipe(d, log, &events);
  EXPECT_EQ(events, 3) << r.stop_reason;
  EXPECT_EQ(r.stop_reason, "");
  EXPECT_EQ(r.bytes_read, static_cast<int64_t>(log.size()));
  EXPECT_FALSE(r.problem("pipe"));
  // The same with a broken tail: the events before it, and the reason.
  r = readThroughPipe(d, log + "xyz", &events);
  EXPECT_EQ(events, 2);
  EXPECT_NE(r.stop_reason.find("is not followed by another event"), std::string::npos) << r.stop_reason;

  rusage before{};
  getrusage(RUSAGE_SELF, &before);
  r = readThroughPipe(d, rawLogEvent(0, "A", "x", 0x3fffffff), &events);  // 1 GiB declared, 1 byte sent
  rusage after{};
  getrusage(RUSAGE_SELF, &after);
  EXPECT_EQ(events, 0);
  EXPECT_NE(r.stop_reason.find("an event cut short"), std::string::npos) << r.stop_reason;
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 64 * 1024) << "peak resident memory grew by KiB";
}

TEST(LogFiles, AnAtomicWriterShowsNothingAtThePathUntilCommit) {
  Dir d;
  const std::string path = d.file("out.lcm");
  {
    lcmio::LogWriter w(path, lcmio::LogWriter::Mode::kAtomic);
    writeOdometry(w, 10);
    EXPECT_FALSE(fs::exists(path));
    EXPECT_TRUE(fs::exists(path + ".partial"));
  }  // no commit: a run that stopped part-way
  EXPECT_FALSE(fs::exists(path)) << "a short log must not appear complete";
  {
    lcmio::LogWriter w(path, lcmio::LogWriter::Mode::kAtomic);
    writeOdometry(w, 10);
    w.commit();
    EXPECT_THROW(writeOdometry(w, 1), std::runtime_error);
  }
  EXPECT_FALSE(fs::exists(path + ".partial"));
  EXPECT_EQ(count(path), 10);
}

// A write that fails (here: past RLIMIT_FSIZE, as a full disk) may leave a torn event where the
// readers stop. The writer then writes nothing more, so nothing is added that nobody can read, and
// commit() reports it without giving the log its final name.
TEST(LogFiles, AfterAFailedWriteNothingMoreIsWrittenAndCommitSaysSo) {
  Dir d;
  const std::string path = d.file("out.lcm");
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);  // the write then fails with EFBIG
  rlimit lim{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &lim), 0);
  std::vector<uint8_t> payload(10000, 0xab);
  int failures = 0;
  std::string first, later;
  lcmio::LogWriter w(path, lcmio::LogWriter::Mode::kAtomic);
  rlimit small = lim;
  small.rlim_cur = 55000;  // room for about five events
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  for (int i = 0; i < 10; ++i) {
    try {
      w.write(1000 + i, "IMAGE", payload.data(), static_cast<int32_t>(payload.size()));
    } catch (const std::exception& e) {
      (failures++ == 0 ? first : later) = e.what();
    }
  }
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &lim), 0);  // space again: nothing may be appended after the tear
  const int64_t before = w.events();
  for (int i = 0; i < 20; ++i) EXPECT_THROW(w.write(2000 + i, "ODOMETRY", payload.data(), 100), std::runtime_error);
  std::string commit_error;
  try {
    w.commit();
  } catch (const std::exception& e) {
    commit_error = e.what();
  }
  std::signal(SIGXFSZ, old_handler);
  EXPECT_GE(failures, 1);
  EXPECT_NE(first.find("failed"), std::string::npos) << first;
  // The system's reason is in the message (RLIMIT_FSIZE: EFBIG), not only "failed".
  EXPECT_EQ(w.failure(), std::strerror(EFBIG));
  EXPECT_NE(first.find(std::strerror(EFBIG)), std::string::npos) << first;
  EXPECT_NE(later.find("an earlier write failed"), std::string::npos) << later;
  EXPECT_EQ(w.events(), before);
  EXPECT_GE(before, 1);
  EXPECT_LT(before, 10);
  EXPECT_NE(commit_error.find("ends at the failed write"), std::string::npos) << commit_error;
  EXPECT_FALSE(fs::exists(path)) << "a log that stops short must not take the final name";
  int64_t odometry = 0, read = 0;
  lcmio::forEachEvent(path + ".partial", [&](const lcmio::LogEvent& e) {
    ++read;
    odometry += e.channel == "ODOMETRY";
  });
  EXPECT_EQ(odometry, 0);
  EXPECT_LE(read, before);
}

// An event counts once it is complete in the file, not once it is in a buffer, and the ones a
// failing write or flush keeps out are counted as lost (counted at the buffer, a full disk showed
// 714 reported for 687 in the file; /dev/full 27 for none).
TEST(LogFiles, AfterAFailureTheCountIsWhatTheFileHolds) {
  Dir d;
  const std::string path = d.file("out.lcm");
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);  // the write then fails with EFBIG
  rlimit lim{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &lim), 0);
  std::vector<uint8_t> payload(200, 0xab);
  int64_t taken = 0, failures = 0;
  lcmio::LogWriter w(path);
  rlimit small = lim;
  small.rlim_cur = 50000;  // room for 215 events of 232 bytes and a torn one
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  for (int i = 0; i < 1000; ++i) {
    try {
      w.write(1000 + i, "POSE", payload.data(), static_cast<int32_t>(payload.size()));
      ++taken;
    } catch (const std::exception&) {
      ++failures;
    }
  }
  EXPECT_THROW(w.commit(), std::runtime_error);
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &lim), 0);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_GE(failures, 1);
  EXPECT_EQ(w.events(), count(path)) << "events reported written against events in the file";
  EXPECT_EQ(w.events(), 50000 / (28 + 4 + 200));
  EXPECT_EQ(w.events() + w.lost(), taken) << "every event taken is in the file or lost";
  // The bytes are those of the complete events, not of the torn one after them (the recorder's
  // MB figure counted every message taken, lost ones too).
  EXPECT_EQ(w.bytes(), w.events() * (28 + 4 + 200));
  EXPECT_LT(w.bytes(), static_cast<int64_t>(fs::file_size(path)));
}

TEST(LogFiles, TheBytesReportedAreTheFilesSize) {
  Dir d;
  const std::string path = d.file("out.lcm");
  lcmio::LogWriter w(path);
  std::vector<uint8_t> payload(1000, 0x5a);
  for (int i = 0; i < 100; ++i) {  // 100 kB: three buffers written, the rest waiting for commit()
    w.write(1000 + i, "IMAGE", payload.data(), static_cast<int32_t>(payload.size()));
    EXPECT_EQ(w.bytes(), (i + 1) * (28 + 5 + 1000));
  }
  w.commit();
  EXPECT_EQ(w.bytes(), static_cast<int64_t>(fs::file_size(path)));
}

TEST(LogFiles, OnAFullDeviceNoEventCountsAsWritten) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this machine";
  lcmio::LogWriter w("/dev/full");
  writeOdometry(w, 27);  // fewer bytes than a buffer: they all wait for commit()
  EXPECT_EQ(w.events(), 27);
  EXPECT_THROW(w.commit(), std::runtime_error);
  EXPECT_EQ(w.events(), 0);
  EXPECT_EQ(w.lost(), 27);
  EXPECT_EQ(w.bytes(), 0);
}

// A recorder flushes now and then so that a SIGKILL loses at most what came since: the flushed
// events are complete in the file before commit(), readable by LCM's own reader, and a failing
// flush is reported once and counts its events as lost.
TEST(LogFiles, FlushedEventsAreInTheFileBeforeCommit) {
  Dir d;
  const std::string path = d.file("out.lcm");
  lcmio::LogWriter w(path);
  writeOdometry(w, 10);  // far less than a buffer
  EXPECT_EQ(fs::file_size(path), 0u);
  w.flushBuffered();
  EXPECT_EQ(static_cast<int64_t>(fs::file_size(path)), w.bytes());
  EXPECT_EQ(count(path), 10);
  lcm::LogFile lcm_reader(path, "r");
  ASSERT_TRUE(lcm_reader.good());
  int64_t read_by_lcm = 0;
  while (lcm_reader.readNextEvent() != nullptr) ++read_by_lcm;
  EXPECT_EQ(read_by_lcm, 10);
  w.flushBuffered();  // nothing buffered: nothing written
  EXPECT_EQ(count(path), 10);
  writeOdometry(w, 5);
  w.commit();
  EXPECT_EQ(count(path), 15);
  EXPECT_EQ(static_cast<int64_t>(fs::file_size(path)), w.bytes());
  EXPECT_THROW(w.flushBuffered(), std::runtime_error);  // after commit()

  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this machine";
  lcmio::LogWriter full("/dev/full");
  writeOdometry(full, 3);
  EXPECT_THROW(full.flushBuffered(), std::runtime_error);
  EXPECT_EQ(full.events(), 0);
  EXPECT_EQ(full.lost(), 3);
  EXPECT_NO_THROW(full.flushBuffered());  // the failure was reported once
  EXPECT_THROW(full.commit(), std::runtime_error);
}

TEST(LogFiles, AnOutputThatIsTheInputIsRefused) {
  Dir d;
  { lcmio::LogWriter w(d.file("in.lcm")); }
  EXPECT_THROW(lcmio::requireDistinctFiles(d.file("in.lcm"), d.file("in.lcm"), "--out"), std::invalid_argument);
  EXPECT_THROW(lcmio::requireDistinctFiles(d.file("in.lcm"), d.path + "/./in.lcm", "--out"), std::invalid_argument);
  fs::create_symlink(d.file("in.lcm"), d.file("link.lcm"));
  try {
    lcmio::requireDistinctFiles(d.file("in.lcm"), d.file("link.lcm"), "--out");
    FAIL() << "a symlink to the input was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--out: '"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(lcmio::requireDistinctFiles(d.file("in.lcm"), d.file("new.lcm"), "--out"));
}

}  // namespace
