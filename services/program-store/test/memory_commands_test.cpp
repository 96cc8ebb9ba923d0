// Balt-System's memory commands against the program store library (manual ln 1740-2134, 7783-8043; the
// catalogue's worked fragments 30-40 of seed-balt.md §12.2).
#include "cell/program_store/memory_commands.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "cell/error/error.h"
#include "cell/program_store/program_store.h"

namespace cell::program_store {
namespace {

namespace fs = std::filesystem;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

const char* kP9 = "%:P9\nN1 T1.1 M6 S200 M3 M7\nN2 G0 X100 Y50 Z100\nM30\n";  // ln 7791-7813

class Memories : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "cell-memory-commands-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    StoreOptions o;
    o.data_dir = dir_;
    o.namespaces = {"BS01", "BS01/MP0", "BS01/MP2", "BS01/MP3", "BS01/MP4", "BS01/MP5", "BS01/MP6"};
    for (const auto& ns : o.namespaces) o.namespace_dialects[ns] = interp::FindDialect("balt");
    store_ = std::make_unique<ProgramStore>(o);
    backend_ = std::make_unique<StoreMemory>(*store_);
  }
  void TearDown() override {
    backend_.reset();
    store_.reset();
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  void Put(const std::string& node, const std::string& name, const std::string& text) {
    PutRequest r;
    r.node = node;
    r.name = name;
    r.content = text;
    store_->Put(r);
  }
  MemoryCommandResult Cmd(const std::string& c, bool yes = false) {
    return RunMemoryCommand(*backend_, "BS01", c, yes);
  }
  // The refusal's code and message; the store is checked unchanged by the caller.
  void Refused(const std::string& c, Errc code, const std::string& needle, bool yes = false) {
    try {
      Cmd(c, yes);
      ADD_FAILURE() << c << ": expected " << needle;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), code) << e.what();
      EXPECT_THAT(e.what(), HasSubstr(needle)) << c;
    }
  }
  std::vector<std::string> Names(const std::string& node) {
    std::vector<std::string> out;
    for (const auto& f : store_->List(node, "*")) out.push_back(f.name);
    return out;
  }
  fs::path dir_;
  std::unique_ptr<ProgramStore> store_;
  std::unique_ptr<StoreMemory> backend_;
};

TEST_F(Memories, NamespacesOfTheMemories) {
  EXPECT_EQ(MemoryNamespace("BS01", ""), "BS01");
  EXPECT_EQ(MemoryNamespace("BS01", "MP1"), "BS01");
  EXPECT_EQ(MemoryNamespace("BS01", "MP2"), "BS01/MP2");
  EXPECT_EQ(MemoryNamespace("BS01", "HOST"), "HOST");
  EXPECT_THROW(MemoryNamespace("BS01", "PR"), Error);  // the tape reader is not on the cell
  EXPECT_TRUE(IsMemoryProgramName("PROG1"));
  EXPECT_FALSE(IsMemoryProgramName("PROGRAM"));  // 7 characters (ln 1981)
  EXPECT_FALSE(IsMemoryProgramName("1PROG"));
}

// COP with renaming across memories and the default MP1 (ln 2068-2080), COP,NAME on the screen (ln 2082).
TEST_F(Memories, CopyBetweenMemoriesWithAndWithoutRenaming) {
  Put("BS01/MP2", "P9", kP9);
  auto r = Cmd("COP, P9/MP2, P2/MP3");
  EXPECT_EQ(r.message, "[FILMS2 03] COMMAND EXECUTED");
  EXPECT_THAT(Names("BS01/MP3"), ElementsAre("P2"));
  EXPECT_EQ(store_->Get("BS01/MP3", "P2").content, kP9);
  Put("BS01", "P24", kP9);
  Cmd("COP P24, /MP2");  // the name kept; the source in MP1
  EXPECT_THAT(Names("BS01/MP2"), ElementsAre("P24", "P9"));
  Cmd("COP,P24,P25");  // a copy in the same memory (ln 7920)
  EXPECT_THAT(Names("BS01"), ElementsAre("P24", "P25"));
  auto shown = Cmd("COP,P24");
  EXPECT_EQ(shown.message, "[FILMS2 06] FILE DISPLAYED");
  ASSERT_EQ(shown.lines.size(), 4u);
  EXPECT_EQ(shown.lines[0], "%:P9");
  // To and from the cell's host.
  Cmd("COP,P24,/HOST");
  EXPECT_THAT(Names("HOST"), ElementsAre("P24"));
}

TEST_F(Memories, CopyRefusals) {
  Put("BS01/MP2", "P9", kP9);
  Put("BS01/MP3", "P9", "%:P9\nM30\n");
  // The destination exists: FILMS2 05 EXISTS DELETE??? without an answer; Y replaces (a new revision).
  Refused("COP,P9/MP2,/MP3", Errc::kAlreadyExists, "[FILMS2 05] EXISTS DELETE??? (Y/N): P9/MP3");
  EXPECT_EQ(store_->Get("BS01/MP3", "P9").content, "%:P9\nM30\n");
  Cmd("COP,P9/MP2,/MP3", true);
  EXPECT_EQ(store_->Get("BS01/MP3", "P9").content, kP9);
  Refused("COP,Q1/MP2,/MP3", Errc::kNotFound, "[FILMS1 05] FILE NOT FOUND IN BUBBLE OR CMOS: Q1/MP2");
  Refused("COP,P9/MP2,/PR", Errc::kInvalidArgument, "[FILMS1 04] PERIPHERAL ERROR");
  Refused("COP,P9/MP2,PROGRAM9/MP3", Errc::kInvalidArgument, "[FILMS1 09] FORMAT ERROR");
  Refused("COP,P9/MP2,/MP2", Errc::kInvalidArgument, "[FILMS1 14] ILLEGAL REQUEST");
  Refused("XYZ,P9", Errc::kInvalidArgument, "[FILMS1 08] INVALID COMMAND");
  // Wildcards cannot rename (ln 8014-8018): A*->B* is FILMS1 10, several files onto one FILMS1 14.
  Refused("COP,P*/MP2,Q*/MP4", Errc::kInvalidArgument, "[FILMS1 10] SYNTAX ERROR");
  Refused("COP,P*/MP2,Q/MP4", Errc::kInvalidArgument, "[FILMS1 14] ILLEGAL REQUEST");
  EXPECT_TRUE(Names("BS01/MP4").empty());
  // A protected destination is not replaced even with Y (FILMS3 26).
  Cmd("ATT,P9/MP3,100");
  Refused("COP,P9/MP2,/MP3", Errc::kPermissionDenied, "[FILMS3 26] WRITE PROTECTED FILE", true);
}

// Wildcards: prefix, suffix, inside, and the whole memory (ln 7988-8012).
TEST_F(Memories, WildcardCopiesAndDirectory) {
  for (const char* n : {"AB1", "ABFIL", "XFIL", "ABCFXL", "Z9"}) Put("BS01/MP2", n, kP9);
  Cmd("COP,AB*/MP2,/MP4");
  EXPECT_THAT(Names("BS01/MP4"), ElementsAre("AB1", "ABCFXL", "ABFIL"));
  Cmd("COP,*FIL/MP2,/MP5");
  EXPECT_THAT(Names("BS01/MP5"), ElementsAre("ABFIL", "XFIL"));
  Cmd("COP,AB*F*L*/MP2,/MP6");
  EXPECT_THAT(Names("BS01/MP6"), ElementsAre("ABCFXL", "ABFIL"));
  Cmd("COP,/MP2,/MP0");  // = COP,*/MP2,/MP0
  EXPECT_EQ(Names("BS01/MP0").size(), 5u);
  // DIR: names and 128-byte sectors (kP9 is 50 bytes: 1 sector), hidden files left out (ln 1814-1843).
  auto dir = Cmd("DIR,AB*/MP2");
  EXPECT_THAT(dir.lines, ElementsAre("NAME   SECT", "AB1       1", "ABCFXL    1", "ABFIL     1", "3 FILES"));
  Cmd("ATT,ABFIL/MP2,HIDDEN");
  EXPECT_THAT(Cmd("DIR/MP2").lines, ElementsAre("NAME   SECT", "AB1       1", "ABCFXL    1", "XFIL      1",
                                                "Z9        1", "4 FILES"));
  Cmd("ATT,ABFIL/MP2,DISPROT");  // clears HIDDEN too
  EXPECT_EQ(Cmd("DIR,MP2").lines.size(), 7u);
}

TEST_F(Memories, RenameDeleteAndAttributes) {
  Put("BS01", "P99", kP9);
  Put("BS01", "PROG1", kP9);
  Cmd("REN, P99, PR1");  // ln 2088
  EXPECT_THAT(Names("BS01"), ElementsAre("PR1", "PROG1"));
  Refused("REN,PR1,PROG1", Errc::kAlreadyExists, "[FILMS1 14] ILLEGAL REQUEST");
  Cmd("ATT,PROG1,100");
  Refused("DEL,PROG1", Errc::kPermissionDenied, "[FILMS3 26] WRITE PROTECTED FILE: PROG1");
  Refused("REN,PROG1,PROG2", Errc::kPermissionDenied, "[FILMS3 26]");
  Cmd("ATT,PROG1,0");
  Cmd("DEL, PROG1");  // ln 2096
  EXPECT_THAT(Names("BS01"), ElementsAre("PR1"));
  // [ALL] asks FILMS2 02 first.
  Put("BS01/MP2", "A1", kP9);
  Put("BS01/MP2", "A2", kP9);
  Refused("DEL,/MP2", Errc::kFailedPrecondition, "[FILMS2 02] DO YOU CONFIRM? (Y/N)");
  EXPECT_EQ(Names("BS01/MP2").size(), 2u);
  Cmd("DEL,/MP2", true);
  EXPECT_TRUE(Names("BS01/MP2").empty());
  Refused("DEL,NOPE", Errc::kNotFound, "[FILMS1 05]");
}

// SPG/REL: a selected program cannot be edited or deleted (ln 1913, 2202-2203); one selection per station.
TEST_F(Memories, SelectedProgramIsLockedUntilReleased) {
  Put("BS01/MP2", "P9", kP9);
  Put("BS01", "P1", kP9);
  Cmd("SPG,P9/MP2");
  EXPECT_TRUE(store_->Get("BS01/MP2", "P9").file.is_selected);
  Refused("DEL,P9/MP2", Errc::kPermissionDenied, "[FILMS3 20] INVALID OPERATION: P9 is selected (SPG)");
  Refused("COP,P1,P9/MP2", Errc::kPermissionDenied, "[FILMS3 20]", true);
  // The store itself refuses too (a `cellctl program rm` or put that goes round the commands).
  try {
    store_->Delete("BS01/MP2", "P9");
    ADD_FAILURE() << "deleted a selected program";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("is selected for execution (SPG); release it (REL) first"));
  }
  Cmd("SPG,P1");  // selecting another releases the first
  EXPECT_FALSE(store_->Get("BS01/MP2", "P9").file.is_selected);
  EXPECT_TRUE(store_->Get("BS01", "P1").file.is_selected);
  Cmd("REL");
  EXPECT_FALSE(store_->Get("BS01", "P1").file.is_selected);
  Cmd("DEL,P9/MP2");
  Refused("SPG,P9/MP2", Errc::kNotFound, "[FILMS1 05]");
}

TEST_F(Memories, DifferencesAndInitialise) {
  Put("BS01/MP2", "PROG1", kP9);
  Put("HOST", "PROG1", kP9);
  auto same = Cmd("DIF,PROG1/MP2,PROG1/HD");  // ln 7985
  EXPECT_FALSE(same.differ);
  EXPECT_EQ(same.message, "[FILMS2 03] COMMAND EXECUTED");
  PutRequest r;
  r.node = "HOST";
  r.name = "PROG1";
  r.content = "%:P9\nN1 T1.1 M6 S200 M3 M7\nN2 G0 X100 Y60 Z100\nM30\n";
  r.force = true;
  store_->Put(r);
  auto diff = Cmd("DIF,PROG1/MP2,/HOST");
  EXPECT_TRUE(diff.differ);
  EXPECT_EQ(diff.message, "[FILMS2 09] DO YOU CONTINUE? (Y/N)");
  EXPECT_THAT(diff.lines, ElementsAre("3: < N2 G0 X100 Y50 Z100", "3: > N2 G0 X100 Y60 Z100"));
  // INI erases the memory, the offsets, origins and tool-life files with it (ln 7948-7957).
  Put("BS01/MP3", "FILEOR", "0 X0 Y0 Z0\n");
  Put("BS01/MP3", "GE1TOL", "VTU,1,T1,[TOOL COMP]1,t60,t2,t60,B\n");
  Cmd("ATT,FILEOR/MP3,100");
  Refused("INI,NAME,/MP3", Errc::kFailedPrecondition, "[FILMS2 02]");
  Cmd("INI,NAME,/MP3", true);
  EXPECT_TRUE(Names("BS01/MP3").empty());
  Cmd("SPG,PROG1/MP2");
  Refused("INI,NAME,/MP2", Errc::kPermissionDenied, "[FILMS3 20]", true);
  EXPECT_THAT(Names("BS01/MP2"), ElementsAre("PROG1"));
}

// A memory holds 64,000 characters (ln 223): a copy that would overfill the destination is FILMS3 15 NO FREE
// SECTORS (ln 9758-9759) and copies nothing; HOST has no such bound. 40,000 + 20,000 = 60,000 fit, a third
// file of 20,000 makes 80,000 > 64,000; replacing the 20,000 file by one of 24,000 makes exactly 64,000.
TEST_F(Memories, CopyStopsAtTheMemorysCapacity) {
  const std::string big = "%:BIG\n" + std::string(40000 - 7, 'X') + "\n";
  const std::string mid = "%:MID\n" + std::string(20000 - 7, 'Y') + "\n";
  const std::string more = "%:MORE\n" + std::string(24000 - 8, 'Z') + "\n";
  ASSERT_EQ(big.size() + mid.size(), 60000u);
  ASSERT_EQ(more.size(), 24000u);
  Put("HOST", "BIG", big);
  Put("HOST", "MID", mid);
  Put("HOST", "MORE", more);
  Cmd("COP,BIG/HOST,BIG/MP2");
  Cmd("COP,MID/HOST,MID/MP2");
  Refused("COP,MID/MP2,MID2/MP2", Errc::kFailedPrecondition, "[FILMS3 15] NO FREE SECTORS");
  Refused("COP,*/HOST,/MP4", Errc::kFailedPrecondition, "[FILMS3 15]");  // 84,000 in all
  EXPECT_TRUE(Names("BS01/MP4").empty());
  EXPECT_THAT(Names("BS01/MP2"), ElementsAre("BIG", "MID"));
  Cmd("COP,MORE/HOST,MID/MP2", true);  // 40,000 + 24,000 = 64,000: full, not over
  Cmd("COP,*/MP2,/HOST", true);        // HOST is the hard disk: no bound
}

}  // namespace
}  // namespace cell::program_store
