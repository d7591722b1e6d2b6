// A full disk under the launcher (issue 47): the run is recorded into a small tmpfs (700 KiB) that a
// publisher fills within seconds. The recorder says WRITE FAILED with the system's reason at once, the
// launcher applies its default policy for a dead recorder (stop the run at once, without the drain,
// exit 1), and what was lost is known exactly: omnislam-logstat reads every complete event of the torn
// file (as many as the recorder says are in it), and the publisher's count of rounds minus the
// images in the file is what the run published unrecorded. Needs root (mount): skips saying so.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <regex>
#include <string>

#include "omnislam/lcmio/channels.h"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

/// A tmpfs of `size` mounted on a fresh folder for the test's life; why not, when it cannot be.
class SmallTmpfs {
 public:
  explicit SmallTmpfs(const std::string& size) {
    const auto r = t::run({"mount", "-t", "tmpfs", "-o", "size=" + size, "tmpfs", dir_.path()}, 20);
    if (r.exit_code != 0) why_not_ = "cannot mount a tmpfs (needs root or CAP_SYS_ADMIN): " + r.output;
  }
  ~SmallTmpfs() {
    if (why_not_.empty()) t::run({"umount", "-l", dir_.path()}, 20);
  }
  const std::string& whyNot() const { return why_not_; }
  std::string file(const std::string& name) const { return dir_.file(name); }

 private:
  t::TempDir dir_;
  std::string why_not_;
};

TEST(FullDisk, TheRecorderSaysSoAtOnceTheRunStopsAndTheLossIsCountedExactly) {
  SmallTmpfs disk("700k");
  if (!disk.whyNot().empty()) GTEST_SKIP() << disk.whyNot();
  t::TempDir dir;
  const std::string launch = dir.file("launch.yaml"), log = disk.file("run.lcm");
  std::ofstream(launch) << "name: fulldisk\nstop_grace_s: 2\ndrain_s: 0.5\nprocesses:\n"
                        << "  - {name: samples, cmd: [omnislam-publish-samples, --duration, '60', --period, '0.02']}\n";
  t::Child launcher({t::binPath("omnislam-launch"), launch, "--log-file", log, "--url", t::privateUdpUrl(36)});
  ASSERT_TRUE(launcher.waitForOutput(
      "[record] WRITE FAILED, recording stopped: writing LCM log '" + log + "' failed: No space left on device", 40))
      << launcher.output();
  const auto failed_seen = std::chrono::steady_clock::now();
  ASSERT_TRUE(
      launcher.waitForOutput("omnislam-record died (exit code 1): the run is not being recorded; stopping it "
                             "now, without the drain",
                             5))
      << launcher.output();
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - failed_seen).count(), 1.0)
      << launcher.output();
  const auto r = launcher.wait(30);
  ASSERT_FALSE(r.timed_out) << r.output;
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("done with errors"), std::string::npos) << r.output;

  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("\\[record\\] ([0-9]+) events in the file"))) << r.output;
  const long in_file = std::stol(m[1]);
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("published ([0-9]+) rounds"))) << r.output;
  const long rounds = std::stol(m[1]);
  const auto stat = t::run({t::binPath("omnislam-logstat"), log}, 20);
  ASSERT_EQ(stat.exit_code, 0) << stat.output;
  // Every complete event is read; only the torn tail is named as unreadable.
  long read = 0;
  std::istringstream lines(stat.output);
  std::string line;
  bool table = false;
  while (std::getline(lines, line)) {
    if (line.rfind("channel ", 0) == 0) table = true;
    else if (line.empty()) table = false;
    else if (table) read += std::stol(t::wordsOfLine(line, line.substr(0, line.find(' ')))[2]);
  }
  EXPECT_EQ(read, in_file) << stat.output << r.output;
  EXPECT_NE(stat.output.find("cannot be read (truncated or corrupt)"), std::string::npos) << stat.output;
  const auto images = t::wordsOfLine(stat.output, channels::kOmniImage);
  ASSERT_GE(images.size(), 4u) << stat.output;
  const long recorded = std::stol(images[2]), gaps = std::stol(images[3]);
  EXPECT_EQ(gaps, 0) << stat.output;  // nothing lost before the disk was full
  // Published = recorded + unrecorded, the unrecorded ones those published after the disk was full.
  // How many there are depends on how soon the launcher stops the publisher after the recorder's
  // failure: none when that is within one period (20 ms) and the torn event was not an image (seen
  // once in a suite run: 392 of 392). Fewer published than recorded would be a miscount.
  EXPECT_GE(rounds, recorded) << "published after the disk was full, unrecorded: " << r.output;
  std::cout << "disk full after " << recorded << " of " << rounds << " rounds; " << rounds - recorded
            << " rounds published unrecorded before the run stopped; " << in_file << " events in the file\n";
}

}  // namespace
