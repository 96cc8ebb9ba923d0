#include "cell/inspection/records.h"

#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>

#include <gtest/gtest.h>

#include "cell/error/error.h"
#include "cell/testing/process.h"

namespace fs = std::filesystem;
using cell::inspection::Records;
using cell::testing::ScopedTempDir;

namespace {
nlohmann::json RunRecord(long id) {
  return {{"station", "KT01"},
          {"dispatch_id", id},
          {"pallet", 3},
          {"programs", {"PUMP341"}},
          {"started", "2026-11-22T03:00:00Z"},
          {"finished", "2026-11-22T03:01:00Z"},
          {"machine_s", 41.5}};
}
}  // namespace

TEST(Records, StoresListsAndReadsRunRecords) {
  ScopedTempDir dir("cell-records-");
  Records r(dir.path());
  EXPECT_EQ(r.StoreRun(RunRecord(7)), "run-KT01-7.json");
  EXPECT_EQ(r.StoreRun(RunRecord(7)), "run-KT01-7.json");  // a retried store is harmless
  r.StoreRun(RunRecord(8));
  auto list = r.List("run-KT01-*");
  ASSERT_EQ(list.size(), 2u);
  EXPECT_EQ(list[0]["name"], "run-KT01-7.json");
  EXPECT_EQ(list[0]["station"], "KT01");
  auto text = r.Cat("run-KT01-8.json");
  ASSERT_TRUE(text);
  EXPECT_EQ(nlohmann::json::parse(*text)["machine_s"], 41.5);
  EXPECT_FALSE(r.Cat("../etc/passwd"));
}

// `inspect ls --after NAME` (DESIGN §6): by name in byte order, the cursor exclusive, sizes of what is shown;
// after the last name and in an empty directory there is nothing.
TEST(Records, ListPagesAfterACursorByName) {
  ScopedTempDir dir("cell-records-");
  Records r(dir.path());
  auto page = [&](const std::string& pattern, const std::string& after, std::size_t limit) {
    std::vector<std::string> out;
    r.List(pattern, after, [&](const cell::records::InspectionEntry& e) {
      if (out.size() == limit) return false;
      EXPECT_TRUE(e.size.has_value()) << e.name;
      out.push_back(e.name);
      return true;
    });
    return out;
  };
  EXPECT_TRUE(page("*", "", 10).empty());
  for (long id : {9, 10, 11}) r.StoreRun(RunRecord(id));
  r.StoreFile("KT01", "PUMP341", "1 2 3\n");
  // "KT01/PUMP341" < "run-KT01-10.json" < "run-KT01-11.json" < "run-KT01-9.json" (bytes, not numbers).
  using V = std::vector<std::string>;
  EXPECT_EQ(page("*", "", 2), (V{"KT01/PUMP341", "run-KT01-10.json"}));
  EXPECT_EQ(page("*", "run-KT01-10.json", 2), (V{"run-KT01-11.json", "run-KT01-9.json"}));
  EXPECT_EQ(page("run-*", "a", 1), (V{"run-KT01-10.json"}));
  EXPECT_TRUE(page("*", "run-KT01-9.json", 10).empty());
  // Names are relative to the directory however it was written (a trailing separator, `.` and `//` in it).
  for (const std::string& spelled :
       {fs::path(dir.path()).string() + "/",
        fs::path(dir.path()).parent_path().string() + "/.//" + fs::path(dir.path()).filename().string()}) {
    auto rows = Records(spelled).List("*");
    ASSERT_EQ(rows.size(), 4u) << spelled;
    EXPECT_EQ(rows[0]["name"], "KT01/PUMP341") << spelled;
  }
}

TEST(Records, RejectsIncompleteRecordsAndBadNames) {
  ScopedTempDir dir("cell-records-");
  Records r(dir.path());
  EXPECT_THROW(r.StoreRun({{"station", "KT01"}}), cell::Error);
  auto bad = RunRecord(1);
  bad["station"] = "../x";
  EXPECT_THROW(r.StoreRun(bad), cell::Error);
  EXPECT_THROW(r.StoreFile("KT01", "a/b", "x"), cell::Error);
}

TEST(Records, KilledWriterLeavesOldOrNewContentNeverTorn) {
  ScopedTempDir tmp("cell-records-");
  const fs::path dir = tmp.path();
  Records r(dir);
  std::string big(4 << 20, 'a');
  r.StoreFile("KT01", "PART.INS", "old\n");
  pid_t pid = fork();
  if (pid == 0) {
    Records child(dir);
    for (;;) child.StoreFile("KT01", "PART.INS", big);  // until killed
  }
  usleep(50000);
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  auto text = Records(dir).Cat("KT01/PART.INS");
  ASSERT_TRUE(text);
  EXPECT_TRUE(*text == "old\n" || *text == big) << "torn file of " << text->size() << " bytes";
}
