// The stacks a stuck process leaves in its log: each thread's own frames under its id and name.
#include "cell/stacks/stacks.h"

#include <fcntl.h>
#include <pthread.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <thread>

#include <gtest/gtest.h>

namespace cell::stacks {
namespace {

// A thread named "stack-probe", blocked in read until it is let go.
class BlockedThread {
 public:
  BlockedThread() {
    if (pipe(wake_) != 0) throw std::runtime_error("pipe");
    thread_ = std::thread([this] {
      pthread_setname_np(pthread_self(), "stack-probe");
      tid_ = ThisThread();
      char c;
      ssize_t n = read(wake_[0], &c, 1);  // blocked here while its stack is taken
      (void)n;
    });
    while (tid_ == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // into the read
  }
  ~BlockedThread() {
    ssize_t n = write(wake_[1], "x", 1);
    (void)n;
    thread_.join();
    close(wake_[0]);
    close(wake_[1]);
  }
  long tid() const { return tid_; }

 private:
  int wake_[2];
  std::atomic<long> tid_{0};
  std::thread thread_;
};

// What a writer writes to a file, read back.
template <typename Write>
std::string Written(Write write_to) {
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() / ("stacks-" + std::to_string(getpid()));
  const int fd = open(out.c_str(), O_CREAT | O_TRUNC | O_WRONLY | O_CLOEXEC, 0600);
  if (fd < 0) return "(cannot open " + out.string() + ")";
  write_to(fd);
  close(fd);
  std::ifstream in(out);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::filesystem::remove(out);
  return text;
}

// The frames under "thread TID (NAME):", up to the next thread's line.
std::string Section(const std::string& text, long tid, const std::string& name) {
  const std::string head = "thread " + std::to_string(tid) + " (" + name + "):\n";
  const auto at = text.find(head);
  if (at == std::string::npos) return {};
  const auto end = text.find("\nthread ", at + head.size());
  return text.substr(at + head.size(), end == std::string::npos ? end : end - at - head.size());
}

void ExpectBlockedInRead(const std::string& section) {
  EXPECT_EQ(section.find("(no answer)"), std::string::npos) << section;
  // The blocking read (libc's, or a sanitizer's interceptor of it) among its frames.
  EXPECT_TRUE(section.find("(read+") != std::string::npos || section.find("_read+") != std::string::npos)
      << section;
  EXPECT_GE(std::count(section.begin(), section.end(), '\n'), 4) << section;  // and the frames below it
}

// What the bus writes before it ends a process with a stuck receive thread (Participant::Watch): every other
// thread's stack, so that the log shows the call that never returned.
TEST(Stacks, EveryOtherThreadsStackUnderItsIdAndName) {
  BlockedThread probe;
  int answered = 0;
  const std::string text = Written([&](int fd) { answered = WriteThreadStacks(fd); });
  EXPECT_GE(answered, 1);
  EXPECT_EQ(text.find("thread " + std::to_string(ThisThread()) + " "), std::string::npos)
      << "the caller writes no stack of its own";
  const std::string section = Section(text, probe.tid(), "stack-probe");
  ASSERT_FALSE(section.empty()) << text;
  ExpectBlockedInRead(section);
}

// What the daemon writes when a start-up step hangs: the main thread's stack alone, taken from its watcher.
TEST(Stacks, OneThreadsStackAndNoOther) {
  BlockedThread probe;
  BlockedThread other;
  bool answered = false;
  const std::string text = Written([&](int fd) { answered = WriteThreadStack(fd, probe.tid()); });
  EXPECT_TRUE(answered);
  ExpectBlockedInRead(Section(text, probe.tid(), "stack-probe"));
  EXPECT_EQ(text.find("thread " + std::to_string(other.tid()) + " "), std::string::npos) << text;
}

// A thread that is gone answers nothing: a line says so, and the writer does not wait past its bound.
TEST(Stacks, AThreadThatIsGoneIsSaidToGiveNoAnswer) {
  long gone = 0;
  std::thread t([&] { gone = ThisThread(); });
  t.join();
  bool answered = true;
  const std::string text = Written([&](int fd) { answered = WriteThreadStack(fd, gone); });
  EXPECT_FALSE(answered);
  EXPECT_NE(text.find("thread " + std::to_string(gone) + " "), std::string::npos) << text;
  EXPECT_NE(text.find("  (no answer)\n"), std::string::npos) << text;
}

}  // namespace
}  // namespace cell::stacks
