// Files a program writes leave the run through the station core to the inspection writer (StoreRecord with
// INSPECTION_STORE_FILE) and then to the program store as a revision in the node's namespace (SaveFile), and
// the program's completion flags are set only once both have them.
#include "harness.h"

namespace cell::station::testing {
namespace {

using StationFiles = StationHarness;

const cell::InspectionRequest* Stored(const FakeIo& io, const std::string& node, const std::string& name) {
  for (const auto& r : io.records)
    if (r.op() == cell::INSPECTION_STORE_FILE && r.file().station().to_string() == node &&
        r.file().file().to_string() == name)
      return &r;
  return nullptr;
}

// Manual ch. 7: G36 + OIF writes the header (ln 7894-7908), MSG lines with an empty line after each
// (ln 8043-8071), G37 closes; OPF/FWR/CLF with the L1050 wait (ln 7997-8004); RCP to HOST (ln 8316-8356).
constexpr const char* kProgram =
    "G71 G90\n"
    "(PAR,L1050=0,L1054=0)\n"
    "N90 G36\n"
    "N100 (OIF,PUMP341)\n"
    "N580 (MSG,THIS IS A TEST.)\n"
    "N950 G37\n"
    "(OPF,DATA7)\n"
    "(PAR,L100=12.5)\n"
    "(FWR,\"X=\",L100)\n"
    "(CLF)\n"
    "(PAR,L1500=L1050)\n"
    "(RCP,DATA7,TO,HOST,DATA7.TXT/AS)\n"
    "(PAR,L1501=L1054)\n"
    "M30\n";

TEST_F(StationFiles, ClosedFilesGoToTheWriterAndSetTheirFlagOnceStored) {
  Put("P", kProgram);
  Dispatch(1, {"P"});
  EXPECT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  const auto* oif = Stored(io_, "KT01", "PUMP341");
  ASSERT_NE(oif, nullptr);
  const std::string text = oif->file().text().to_string();
  EXPECT_EQ(text.substr(0, 22), "CONTROL SERIAL NUMBER ");
  EXPECT_NE(text.find("PALLET CODE/PART NUMBER = 1\n"), std::string::npos) << text;
  EXPECT_NE(text.find("------------------------------\nTHIS IS A TEST.\n\n"), std::string::npos) << text;
  EXPECT_TRUE(oif->file().closed());
  EXPECT_EQ(oif->file().dispatch_id(), 1);
  const auto* data = Stored(io_, "KT01", "DATA7");
  ASSERT_NE(data, nullptr);
  EXPECT_EQ(data->file().text().to_string(), "X=12.500000\n");
  const auto* host = Stored(io_, "HOST", "DATA7.TXT");
  ASSERT_NE(host, nullptr);
  EXPECT_EQ(host->file().text().to_string(), "X=12.500000\n");
  EXPECT_DOUBLE_EQ(Variables()["L1500"], 1.0);  // L1050 after CLF: stored
  EXPECT_DOUBLE_EQ(Variables()["L1501"], 1.0);  // L1054 after RCP
  // The same files in the program store, declared in the station's dialect: the OIF file as an inspection
  // file, OPF's as data; each store under its own idempotency key.
  EXPECT_EQ(io_.programs["KT01/PUMP341"], text);
  EXPECT_EQ(io_.saved_as["KT01/PUMP341"].dialect, "ktapl");
  EXPECT_EQ(io_.saved_as["KT01/PUMP341"].file_type, "inspection");
  EXPECT_EQ(io_.programs["KT01/DATA7"], "X=12.500000\n");
  EXPECT_EQ(io_.saved_as["KT01/DATA7"].file_type, "data");
  EXPECT_EQ(io_.programs["HOST/DATA7.TXT"], "X=12.500000\n");
  EXPECT_NE(io_.saved_as["KT01/DATA7"].idempotency_key, io_.saved_as["HOST/DATA7.TXT"].idempotency_key);
}

TEST_F(StationFiles, AProgramStoreThatIsAwayIsWaitedForAfterTheWriter) {
  Put("P", kProgram);
  io_.store_down = true;
  SetAfter(40, io_.store_down, false);
  Dispatch(1, {"P"});
  EXPECT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_EQ(io_.programs.count("KT01/PUMP341"), 1u);
  EXPECT_DOUBLE_EQ(Variables()["L1500"], 1.0);
  // The writer was asked once per file: the retries were the store's.
  int oif = 0;
  for (const auto& r : io_.records)
    if (r.op() == cell::INSPECTION_STORE_FILE && r.file().file().to_string() == "PUMP341") ++oif;
  EXPECT_EQ(oif, 1);
}

TEST_F(StationFiles, AWriterThatIsAwayIsWaitedForAndNothingIsLost) {
  Put("P", kProgram);
  io_.writer_up = false;
  SetAfter(40, io_.writer_up, true);  // back after about two seconds
  Dispatch(1, {"P"});
  EXPECT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_NE(Stored(io_, "KT01", "PUMP341"), nullptr);
  EXPECT_NE(Stored(io_, "KT01", "DATA7"), nullptr);
  EXPECT_DOUBLE_EQ(Variables()["L1500"], 1.0);
}

TEST_F(StationFiles, NoWriterAtAllFailsTheRunWithAClearReason) {
  Put("P", kProgram);
  io_.writer_up = false;
  Dispatch(1, {"P"});
  cell::RunStatus s = RunOne(1);
  EXPECT_EQ(s.state(), cell::RUN_FAILED);
  EXPECT_NE(s.reason().to_string().find("no inspection writer on the bus"), std::string::npos)
      << s.reason().to_string();
}

// OPF with A/ (ln 7910-7930) continues the file: here one an earlier run stored in the station's namespace;
// the close stores the whole text as the next revision.
TEST_F(StationFiles, AppendContinuesTheFileAnEarlierRunStored) {
  Put("FIRST", "(PAR,L100=1.)\n(OPF,LOG)\n(FWR,\"RUN=\",L100)\n(CLF)\nM30\n");
  Put("SECOND",
      "(PAR,L100=2.,L1050=0)\n(OPF,LOG,A/AS)\n(FWR,\"RUN=\",L100)\n(CLF)\n(PAR,L1500=L1050)\nM30\n");
  Dispatch(1, {"FIRST"});
  EXPECT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_EQ(io_.programs["KT01/LOG"], "RUN=1.0000000\n");  // 8 significant digits (FWR)
  Dispatch(2, {"SECOND"});
  EXPECT_EQ(RunOne(2).state(), cell::RUN_COMPLETED);
  EXPECT_EQ(io_.programs["KT01/LOG"], "RUN=1.0000000\nRUN=2.0000000\n");
  const auto* second = Stored(io_, "KT01", "LOG");
  ASSERT_NE(second, nullptr);
  EXPECT_DOUBLE_EQ(Variables()["L1500"], 1.0);
}

// Two programs of one pallet map that each write a file: every store has its own idempotency key (a key
// shared by the two would make the store take the second for a retry of the first).
TEST_F(StationFiles, EachProgramOfADispatchStoresUnderItsOwnKeys) {
  Put("A", "(OPF,FA)\n(FWR,\"A\")\n(CLF)\nM30\n");
  Put("B", "(OPF,FB)\n(FWR,\"B\")\n(CLF)\nM30\n");
  Dispatch(1, {"A", "B"});
  EXPECT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_EQ(io_.saved_as["KT01/FA"].idempotency_key, "file-KT01-1-1-1");
  EXPECT_EQ(io_.saved_as["KT01/FB"].idempotency_key, "file-KT01-1-2-1");
}

// (DLF,filename) deletes from the control directory, the station's namespace (ln 8006-8041); L1051 is set
// once the store has done it. A name that is not there is already deleted.
TEST_F(StationFiles, DeleteRemovesTheFileFromTheStationsNamespace) {
  Put("OLDDATA", "X=1\n");
  Put("OLDDATA", "X=1\n", "HOST");
  Put("P",
      "(PAR,L1051=0)\n(DLF,OLDDATA)\n(PAR,L1500=L1051,L1051=0)\n(DLF,NEVERTHERE/AS)\n"
      "(PAR,L1501=L1051)\nM30\n");
  Dispatch(1, {"P"});
  EXPECT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_EQ(io_.programs.count("KT01/OLDDATA"), 0u);
  EXPECT_EQ(io_.programs.count("HOST/OLDDATA"), 1u);  // HOST is not the control's directory
  EXPECT_DOUBLE_EQ(Variables()["L1500"], 1.0);
  EXPECT_DOUBLE_EQ(Variables()["L1501"], 1.0);
  ASSERT_EQ(io_.deleted.size(), 2u);
  EXPECT_EQ(io_.deleted[0], "KT01/OLDDATA file-KT01-1-1-1");
  EXPECT_EQ(io_.deleted[1], "KT01/NEVERTHERE file-KT01-1-1-2");
}

TEST_F(StationFiles, DeleteWaitsForAStoreThatIsAway) {
  Put("OLDDATA", "X=1\n");
  Put("P", "(PAR,L1051=0)\n(DLF,OLDDATA)\n(PAR,L1500=L1051)\nM30\n");
  io_.store_down = true;
  SetAfter(40, io_.store_down, false);
  Dispatch(1, {"P"});
  EXPECT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_EQ(io_.programs.count("KT01/OLDDATA"), 0u);
  EXPECT_DOUBLE_EQ(Variables()["L1500"], 1.0);
}

}  // namespace
}  // namespace cell::station::testing
