// omnislam-logstat on a log the test writes: the per-channel table and, per process, its last
// PROCESS_STATUS (counters, state, detail, last error), with an undecodable status event counted
// as bad and not taken for a process; and a decoder for every message type of lcmtypes/.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/image_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/process_status_t.hpp"
#include "omnislam/slam_health_t.hpp"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

process_status_t status(const std::string& name, int64_t seq, int8_t state, int64_t in, int64_t gaps,
                        const std::string& detail, const std::string& error) {
  process_status_t s{};
  s.utime = 1'700'000'000'000'000 + seq * 1'000'000;
  s.seq = seq;
  s.name = name;
  s.pid = 4242;
  s.state = state;
  s.messages_in = in;
  s.messages_out = 2 * in;
  s.decode_errors = 1;
  s.rejected_inputs = 3;
  s.sequence_gaps = gaps;
  s.last_error = error;
  s.detail = detail;
  return s;
}

TEST(Logstat, PrintsEachProcesssLastStatus) {
  t::TempDir dir;
  const std::string path = dir.file("status.lcm");
  {
    lcmio::LogWriter log(path);
    const std::string ch = channels::kProcessStatus;
    log.write(1, ch, status("capture", 0, process_status_t::STATE_RUNNING, 10, 0, "frame 1", ""));
    log.write(2, ch, status("slam", 0, process_status_t::STATE_RUNNING, 5, 0, "", ""));
    const uint8_t garbage[] = {1, 2, 3};
    log.write(3, ch, garbage, 3);
    log.write(4, ch, status("capture", 1, process_status_t::STATE_FINISHED, 77, 12, "frame 9", ""));
    log.write(5, ch, status("slam", 1, process_status_t::STATE_ERROR, 6, 0, "", "OMNI_FEATURES: too old"));
  }
  const auto r = t::run({t::binPath("omnislam-logstat"), path}, 10);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Channel table: 5 events, no gap in either process's own sequence, 1 undecodable.
  const std::vector<std::string> channel{"PROCESS_STATUS", "process_status_t", "5", "0", "1", "0.00", "0.00", "0.00"};
  EXPECT_EQ(t::wordsOfLine(r.output, "PROCESS_STATUS"), channel) << r.output;
  // The last status of each process (pid, state, statuses, in, out, decode, rejected, gaps), not the
  // first; the undecodable event is no process.
  const std::vector<std::string> capture{"capture", "4242", "finished", "2", "77", "154", "1", "3", "12"};
  const std::vector<std::string> slam{"slam", "4242", "error", "2", "6", "12", "1", "3", "0"};
  EXPECT_EQ(t::wordsOfLine(r.output, "capture"), capture) << r.output;
  EXPECT_EQ(t::wordsOfLine(r.output, "slam"), slam) << r.output;
  EXPECT_NE(r.output.find("  capture detail: frame 9\n"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("frame 1"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("  slam last error: OMNI_FEATURES: too old\n"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("slam detail"), std::string::npos) << r.output;  // empty detail: no line
}

// An image whose sizes do not fit its bytes is reported, not read past its buffer by
// --export-images; a truncated log is reported as truncated, not listed as if complete.
TEST(Logstat, BadImagesAndATruncatedTailAreReportedNotFatal) {
  t::TempDir dir;
  const std::string path = dir.file("images.lcm");
  {
    lcmio::LogWriter log(path);
    for (int k = 0; k < 3; ++k) {
      image_t m{};
      m.utime = 1'000'000 + k * 100'000;
      m.seq = k;
      m.camera_name = "cam";
      m.width = 4, m.height = 2, m.row_stride = 4, m.pixel_format = image_t::FORMAT_GRAY8;
      m.data.assign(8, static_cast<uint8_t>(40 * k));
      if (k == 1) m.width = m.height = m.row_stride = 20000;  // sizes that 8 bytes cannot hold
      m.size = static_cast<int32_t>(m.data.size());
      log.write(m.utime, channels::kOmniImage, m);
    }
    // The third repeats the first's utime and seq; the fourth's seq is corrupted far ahead (not
    // some 9e18 missed messages, and a second such jump must not overflow the count);
    // the fifth goes on from the second.
    const int64_t utimes[] = {1'000'000, 1'020'000, 1'000'000, 1'040'000, 1'060'000};
    const int64_t seqs[] = {0, 1, 0, std::numeric_limits<int64_t>::max(), 2};
    odometry_t o{};
    for (int k = 0; k < 5; ++k) {
      o.utime = utimes[k];
      o.seq = seqs[k];
      log.write(o.utime, channels::kOdometry, o);
    }
  }
  const auto r = t::run({t::binPath("omnislam-logstat"), path, "--export-images", dir.file("png")}, 20);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 images written to"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("  OMNI_IMAGE: 1 bad, the first: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("  ODOMETRY: 3 seq restarts (not after the previous one, or over 1000000 ahead of "
                          "it), 1 utime not after the previous one"),
            std::string::npos)
      << r.output;
  const std::vector<std::string> odometry_words = t::wordsOfLine(r.output, "ODOMETRY");
  ASSERT_GE(odometry_words.size(), 5u) << r.output;
  EXPECT_EQ(odometry_words[2], "5") << r.output;  // messages
  EXPECT_EQ(odometry_words[3], "0") << r.output;  // gaps: a jump is not missed messages
  EXPECT_TRUE(std::filesystem::exists(dir.file("png/frame_000000.png")));
  EXPECT_TRUE(std::filesystem::exists(dir.file("png/frame_000002.png")));
  // The same log cut short: listed, with a warning that names it.
  std::filesystem::copy_file(path, dir.file("cut.lcm"));
  std::filesystem::resize_file(dir.file("cut.lcm"), std::filesystem::file_size(path) - 10);
  const auto cut = t::run({t::binPath("omnislam-logstat"), dir.file("cut.lcm")}, 20);
  EXPECT_EQ(cut.exit_code, 0) << cut.output;
  EXPECT_NE(cut.output.find("warning: " + dir.file("cut.lcm") + ": the "), std::string::npos) << cut.output;
  EXPECT_NE(cut.output.find("cannot be read (truncated or corrupt)"), std::string::npos) << cut.output;
}

TEST(Logstat, ALogWithoutStatusHasNoProcessTable) {
  t::TempDir dir;
  const std::string path = dir.file("empty.lcm");
  { lcmio::LogWriter log(path); }
  const auto r = t::run({t::binPath("omnislam-logstat"), path}, 10);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("process (last status)"), std::string::npos) << r.output;
}

// The span is newest minus oldest utime (never negative for a log out of order); a 999-character
// channel name is elided, not the row (its counts and newline stay); a name with a NUL byte is
// printed escaped, not as a second "SLAM_POSE" row.
TEST(Logstat, SpansAreNeverNegativeAndOddChannelNamesKeepTheirRows) {
  t::TempDir dir;
  const std::string path = dir.file("odd.lcm");
  {
    lcmio::LogWriter log(path);
    int64_t seq = 0;
    for (const int64_t s : {100, 1, 50}) {
      odometry_t o{};
      o.utime = s * 1'000'000, o.seq = seq++;
      log.write(o.utime, channels::kOdometry, o);
    }
    const std::vector<uint8_t> junk{1, 2, 3};
    log.write(1, std::string(999, 'L'), junk.data(), 3);
    log.write(1, std::string(999, 'L'), junk.data(), 3);
    log.write(1, std::string("ODOMETRY\0X", 10), junk.data(), 3);
  }
  const auto r = t::run({t::binPath("omnislam-logstat"), path}, 10);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("     99.00"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("-99.00"), std::string::npos) << r.output;
  const std::string long_row = std::string(40, 'L') + "...(999 bytes) ?";
  const auto at = r.output.find(long_row);
  ASSERT_NE(at, std::string::npos) << r.output;
  const std::string row = r.output.substr(at, r.output.find('\n', at) - at);
  EXPECT_NE(row.find("       2 "), std::string::npos) << row;  // its message count
  EXPECT_NE(r.output.find("ODOMETRY\\x00X"), std::string::npos) << r.output;
  size_t odometry_rows = 0;
  for (size_t p = r.output.find("\nODOMETRY "); p != std::string::npos; p = r.output.find("\nODOMETRY ", p + 1))
    ++odometry_rows;
  EXPECT_EQ(odometry_rows, 1u) << r.output;
}

}  // namespace

namespace {

// Two parts of one recording (a recorder restarted into NAME.part2.lcm): read in order, each
// channel's sequence is followed across the files, so exactly what the gap lost is counted, per
// channel and per process, and said per gap; a publisher that restarted in the gap is named.
TEST(Logstat, SeveralPartsAreOneRecordingAndTheGapBetweenThemIsCounted) {
  t::TempDir dir;
  const std::string part1 = dir.file("run.lcm"), part2 = dir.file("run.part2.lcm");
  const auto odometry = [](int64_t seq) {
    odometry_t o{};
    o.utime = 1'000'000 + seq * 20'000;
    o.seq = seq;
    return o;
  };
  {
    lcmio::LogWriter log(part1);
    for (int64_t seq = 0; seq < 10; ++seq) log.write(5'000'000 + seq * 20'000, channels::kOdometry, odometry(seq));
    log.write(5'200'000, channels::kProcessStatus,
              status("odometry", 0, process_status_t::STATE_RUNNING, 1, 0, "", ""));
    log.write(5'200'000, channels::kProcessStatus,
              status("features", 4, process_status_t::STATE_RUNNING, 1, 0, "", ""));
  }
  {
    lcmio::LogWriter log(part2);  // seqs 10..16 lost; odometry's status 1 and 2 lost; features restarted
    log.write(5'540'000, channels::kProcessStatus,
              status("features", 0, process_status_t::STATE_RUNNING, 1, 0, "", ""));
    for (int64_t seq = 17; seq < 20; ++seq) log.write(5'000'000 + seq * 20'000, channels::kOdometry, odometry(seq));
    log.write(6'000'000, channels::kProcessStatus,
              status("odometry", 3, process_status_t::STATE_RUNNING, 1, 0, "", ""));
  }
  const auto r = t::run({t::binPath("omnislam-logstat"), part1, part2}, 10);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // channel type messages gaps ...: 13 of 20 odometry messages, the 7 missing ones as gaps.
  const auto row = t::wordsOfLine(r.output, "ODOMETRY");
  ASSERT_GE(row.size(), 4u) << r.output;
  EXPECT_EQ(row[2], "13") << r.output;
  EXPECT_EQ(row[3], "7") << r.output;
  EXPECT_NE(r.output.find(
                "gap between " + part1 + " and " + part2 +
                ": 0.340 s unrecorded by the recorders' clocks; 9 messages lost by seq: ODOMETRY 7 PROCESS_STATUS 2; "
                "seq restarted across it (a publisher restarted, its losses there are not counted): PROCESS_STATUS"),
            std::string::npos)
      << r.output;
  // One file alone: no gap line, and the same table as before.
  const auto one = t::run({t::binPath("omnislam-logstat"), part1}, 10);
  EXPECT_EQ(one.output.find("gap between"), std::string::npos) << one.output;
  EXPECT_EQ(t::wordsOfLine(one.output, "ODOMETRY")[3], "0") << one.output;
}

}  // namespace

namespace {

/// The struct names of lcmtypes/*.lcm, and those of them used as a field of another (element types
/// such as feature_t, never published alone).
struct ContractTypes {
  std::set<std::string> all, nested;
};

ContractTypes contractTypes() {
  ContractTypes types;
  std::vector<std::string> bodies;
  for (const auto& entry : std::filesystem::directory_iterator(t::sourcePath("lcmtypes"))) {
    if (entry.path().extension() != ".lcm") continue;
    std::ifstream in(entry.path());
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::smatch m;
    if (std::regex_search(text, m, std::regex(R"(\bstruct\s+(\w+))"))) types.all.insert(m[1]);
    bodies.push_back(text);
  }
  const std::regex field(R"(^\s*(\w+)\s+\w+\s*(\[[^\]]*\])?\s*;)", std::regex::multiline);
  for (const std::string& text : bodies)
    for (auto it = std::sregex_iterator(text.begin(), text.end(), field); it != std::sregex_iterator(); ++it)
      if (types.all.count((*it)[1])) types.nested.insert((*it)[1]);
  return types;
}

}  // namespace

// Every message type of lcmtypes/ (all but the element types nested in another) is decoded by
// omnislam-logstat on a channel of the contract, and every type it names exists there: a type
// added to lcmtypes/ without a decoder fails here. lcm-spy decodes by the classes of the types
// jar, which must hold one per type. SLAM_HEALTH, printed "?" before, is shown with its type.
TEST(Logstat, DecodesEveryTypeOfTheContract) {
  const ContractTypes types = contractTypes();
  ASSERT_GE(types.all.size(), 12u);
  EXPECT_EQ(types.nested, (std::set<std::string>{"feature_t", "landmark_t"}));
  const auto r = t::run({t::binPath("omnislam-logstat"), "--list-types"}, 10);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::set<std::string> decoded;
  std::istringstream lines(r.output);
  for (std::string channel, type; lines >> channel >> type;) {
    EXPECT_TRUE(types.all.count(type)) << channel << " " << type << " is not in lcmtypes/";
    decoded.insert(type);
  }
  for (const std::string& type : types.all)
    if (!types.nested.count(type)) EXPECT_TRUE(decoded.count(type)) << type << ": no decoder in logstat\n" << r.output;
  const std::string jar = t::binPath("../java/omnislam-lcmtypes.jar");
  if (std::filesystem::exists(jar)) {  // built when javac and lcm.jar are found (lcmtypes/CMakeLists.txt)
    const auto listing = t::run({"unzip", "-l", jar}, 30);
    ASSERT_EQ(listing.exit_code, 0) << listing.output;
    for (const std::string& type : types.all)
      EXPECT_NE(listing.output.find("omnislam/" + type + ".class"), std::string::npos) << type << " not in " << jar;
  }
  t::TempDir dir;
  const std::string path = dir.file("health.lcm");
  {
    lcmio::LogWriter log(path);
    slam_health_t h{};
    h.reason = "ok";
    h.num_particles = 10;
    h.effective_sample_size = 9.5;
    for (int k = 0; k < 3; ++k) {
      h.utime = 1'000'000 + k * 100'000;
      h.seq = k;
      log.write(h.utime, channels::kSlamHealth, h);
    }
  }
  const auto stat = t::run({t::binPath("omnislam-logstat"), path}, 10);
  ASSERT_EQ(stat.exit_code, 0) << stat.output;
  const std::vector<std::string> row{"SLAM_HEALTH", "slam_health_t", "3", "0", "0", "0.20", "10.00", "0.00"};
  EXPECT_EQ(t::wordsOfLine(stat.output, "SLAM_HEALTH"), row) << stat.output;
}
