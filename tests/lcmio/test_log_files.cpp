// Log files: a truncated or corrupt tail is told apart from the end of the log and named; an
// atomic writer leaves PATH.partial until commit(); an output that is the input is refused.
#include <gtest/gtest.h>

#include <stdlib.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/odometry_t.hpp"

using namespace omnislam;
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
  EXPECT_NE(cut.problem("cut.lcm")->find("the 50 bytes after its first 99 events (from byte 9900 of 9950)"), std::string::npos) << *cut.problem("cut.lcm");
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
