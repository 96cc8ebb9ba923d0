#include "cell/proc/proc.h"

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

namespace {

TEST(StartTime, OfALiveProcessAndNotOfAZombieOrNobody) {
  auto me = cell::proc::StartTime(getpid());
  ASSERT_TRUE(me.has_value());
  EXPECT_EQ(cell::proc::StartTime(getpid()), me);  // the same process, the same start time
  const pid_t child = fork();
  if (child == 0) _exit(0);
  ASSERT_GT(child, 0);
  siginfo_t info{};
  ASSERT_EQ(waitid(P_PID, static_cast<id_t>(child), &info, WEXITED | WNOWAIT), 0);  // ended, not reaped
  EXPECT_FALSE(cell::proc::StartTime(child).has_value()) << "a zombie has ended";
  waitpid(child, nullptr, 0);
  EXPECT_FALSE(cell::proc::StartTime(child).has_value());
  EXPECT_FALSE(cell::proc::StartTime(0).has_value());
  EXPECT_FALSE(cell::proc::StartTime(-1).has_value());
}

TEST(Usage, OfALiveProcessAndOfNobody) {
  const auto rss = cell::proc::ResidentKb(getpid());
  ASSERT_TRUE(rss.has_value());
  EXPECT_GT(*rss, 0);
  const auto before = cell::proc::OpenDescriptors(getpid());
  ASSERT_TRUE(before.has_value());
  const int fd = dup(0);
  ASSERT_GE(fd, 0);
  EXPECT_EQ(cell::proc::OpenDescriptors(getpid()), *before + 1);
  close(fd);
  EXPECT_EQ(cell::proc::OpenDescriptors(getpid()), before);
  EXPECT_FALSE(cell::proc::ResidentKb(-1).has_value());
  EXPECT_FALSE(cell::proc::OpenDescriptors(0).has_value());
}

}  // namespace
