#include "cell/log/log.h"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>

#include <cstdio>
#include <string>

#include "cell/error/error.h"

namespace {

// Everything written to a temporary FILE* so far.
std::string ReadAll(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string out;
  char buf[512];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) out.append(buf, n);
  return out;
}

// Checks that every line starts with an ISO-8601 UTC timestamp "YYYY-MM-DDTHH:MM:SS.mmmZ " and returns the
// text with those timestamps removed ("" if a line lacks one). (No std::regex: GCC 12 warns inside it
// under the sanitizer build.)
std::string StripTimestamps(const std::string& text) {
  const std::string shape = "dddd-dd-ddTdd:dd:dd.dddZ ";
  std::string out;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    end = end == std::string::npos ? text.size() : end + 1;
    std::string line = text.substr(pos, end - pos);
    if (line.size() < shape.size()) return "";
    for (size_t i = 0; i < shape.size(); ++i) {
      bool ok = shape[i] == 'd' ? (line[i] >= '0' && line[i] <= '9') : line[i] == shape[i];
      if (!ok) return "";
    }
    out += line.substr(shape.size());
    pos = end;
  }
  return out;
}

cell::log::Options Opts(std::FILE* out, bool journal) {
  cell::log::Options o;
  o.out = out;
  o.journal = journal;
  return o;
}

class LogTest : public ::testing::Test {
 protected:
  void SetUp() override {
    out_ = std::tmpfile();
    ASSERT_NE(out_, nullptr);
    unsetenv("CELL_LOG_LEVEL");
  }
  void TearDown() override {
    spdlog::set_default_logger(nullptr);
    std::fclose(out_);
    unsetenv("CELL_LOG_LEVEL");
  }
  std::FILE* out_ = nullptr;
};

TEST_F(LogTest, OneLinePerEventNamingServiceAndStation) {
  cell::log::Init("cell-interpreter", "KT01", Opts(out_, false));
  spdlog::info("program {} started", "O1234");
  spdlog::error("two\nlines");
  std::string text = ReadAll(out_);
  EXPECT_EQ(StripTimestamps(text),
            "cell-interpreter[KT01] info: program O1234 started\n"
            "cell-interpreter[KT01] error: two\\nlines\n")
      << text;
}

TEST_F(LogTest, HostServicesHaveNoStation) {
  cell::log::Init("cell-scheduler", "", Opts(out_, true));
  spdlog::warn("backlog {}", 3);
  EXPECT_EQ(ReadAll(out_), "<4>cell-scheduler warning: backlog 3\n");
}

TEST_F(LogTest, LevelComesFromEnvironmentDefaultInfo) {
  cell::log::Init("svc", "", Opts(out_, true));
  spdlog::debug("hidden");
  spdlog::info("shown");
  EXPECT_EQ(ReadAll(out_), "<6>svc info: shown\n");

  std::FILE* second = std::tmpfile();
  setenv("CELL_LOG_LEVEL", "DEBUG", 1);
  cell::log::Init("svc", "", Opts(second, true));
  spdlog::debug("now shown");
  EXPECT_EQ(ReadAll(second), "<7>svc debug: now shown\n");
  spdlog::set_default_logger(nullptr);
  std::fclose(second);
}

TEST_F(LogTest, BadLevelWarnsAndUsesInfo) {
  setenv("CELL_LOG_LEVEL", "loud", 1);
  cell::log::Init("svc", "OK01", Opts(out_, true));
  spdlog::debug("hidden");
  std::string text = ReadAll(out_);
  EXPECT_NE(text.find("<4>svc[OK01] warning: CELL_LOG_LEVEL: log level 'loud' is not one of trace"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("hidden"), std::string::npos);
}

// systemd hands a service its journal stream and names it in JOURNAL_STREAM=<dev>:<inode>; only a
// matching stream gets the journal format (a child that inherited the variable keeps timestamps).
TEST_F(LogTest, JournalFormatWhenStreamMatchesJournalStream) {
  struct stat st {};
  ASSERT_EQ(fstat(fileno(out_), &st), 0);
  setenv("JOURNAL_STREAM", (std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino)).c_str(), 1);
  cell::log::Options o;
  o.out = out_;
  cell::log::Init("cell-scheduler", "", o);
  spdlog::error("disk full");
  EXPECT_EQ(ReadAll(out_), "<3>cell-scheduler error: disk full\n");

  std::FILE* other = std::tmpfile();
  o.out = other;
  cell::log::Init("cell-scheduler", "", o);
  spdlog::error("disk full");
  EXPECT_EQ(StripTimestamps(ReadAll(other)), "cell-scheduler error: disk full\n");
  spdlog::set_default_logger(nullptr);
  std::fclose(other);
  unsetenv("JOURNAL_STREAM");
}

TEST(ParseLevel, AcceptsNamesRejectsOthers) {
  EXPECT_EQ(cell::log::ParseLevel("warn"), spdlog::level::warn);
  EXPECT_EQ(cell::log::ParseLevel("Warning"), spdlog::level::warn);
  EXPECT_EQ(cell::log::ParseLevel("off"), spdlog::level::off);
  EXPECT_THROW(cell::log::ParseLevel("verbose"), cell::Error);
}

}  // namespace
