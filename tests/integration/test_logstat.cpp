// omnislam-logstat on a log the test writes: the per-channel table and, per process, its last
// PROCESS_STATUS (counters, state, detail, last error), with an undecodable status event counted
// as bad and not taken for a process.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/log_writer.h"
#include "omnislam/process_status_t.hpp"
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

TEST(Logstat, ALogWithoutStatusHasNoProcessTable) {
  t::TempDir dir;
  const std::string path = dir.file("empty.lcm");
  { lcmio::LogWriter log(path); }
  const auto r = t::run({t::binPath("omnislam-logstat"), path}, 10);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("process (last status)"), std::string::npos) << r.output;
}

}  // namespace
