// The test harness's Child (tests/support/proc_util.h): a child that cannot be started is reported
// at once (exit code 127, the reason in its output) and never turns into kill(-1) or waitpid(-1),
// which would kill every process of the user or steal another child's exit status.
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <csignal>
#include <vector>

#include "proc_util.h"

TEST(ChildProcess, AChildThatCannotStartIsReportedAndOthersAreUntouched) {
  omnislam::testing::Child other({"sleep", "30"});
  ASSERT_GT(other.pid(), 0);
  ASSERT_TRUE(other.alive());

  // Use up the file descriptors so that pipe() fails.
  rlimit saved{};
  ASSERT_EQ(getrlimit(RLIMIT_NOFILE, &saved), 0);
  rlimit low = saved;
  low.rlim_cur = 64;
  ASSERT_EQ(setrlimit(RLIMIT_NOFILE, &low), 0);
  std::vector<int> held;
  for (int fd; (fd = dup(0)) >= 0;) held.push_back(fd);
  omnislam::testing::RunResult failed;
  {
    omnislam::testing::Child c({"true"});
    EXPECT_EQ(c.pid(), -1);
    EXPECT_FALSE(c.alive());
    failed = c.wait(5.0);
  }
  for (int fd : held) close(fd);
  ASSERT_EQ(setrlimit(RLIMIT_NOFILE, &saved), 0);

  EXPECT_EQ(failed.exit_code, 127);
  EXPECT_FALSE(failed.timed_out);
  EXPECT_NE(failed.output.find("cannot start the child: pipe"), std::string::npos) << failed.output;
  // The other child was neither killed nor reaped by the failed one.
  EXPECT_TRUE(other.alive());
  other.signal(SIGTERM);
  const omnislam::testing::RunResult r = other.wait(10.0);
  EXPECT_FALSE(r.timed_out);
  EXPECT_EQ(r.exit_code, 128 + SIGTERM);
}
