// `cellctl inspect ls|cat|export` against a real cell-inspection-writer (issue 14): an inspection file handed
// over the bus as a station does (STORE_FILE), then listed, shown and exported as text, CSV and QIF 3.0;
// a stored file that is no inspection file, a bad --format and a missing name.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <thread>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/idl/inspection.h"
#include "cell/inspection/inspection_file.h"
#include "cell/names/names.h"
#include "cell/testing/process.h"

using namespace cell::testing;
namespace ins = cell::inspection;

namespace {

class InspectExport : public ::testing::Test {
 protected:
  void SetUp() override {
    data_ = tmp_.path();
    writer_ = std::make_unique<Process>(std::vector<std::string>{BinDir() + "/cell-inspection-writer"},
                                        std::map<std::string, std::string>{{"CELL_DATA_DIR", data_}},
                                        data_ + "/writer.out", data_ + "/writer.err");
  }
  RunResult Ctl(std::vector<std::string> args) {
    args.insert(args.begin(), BinDir() + "/cellctl");
    return RunCommand(args, {{"CELL_DATA_DIR", data_}});
  }
  void Store(const std::string& station, const std::string& file, const std::string& text) {
    cell::bus::Participant bus("inspect-export-test");
    cell::bus::Client<cell::InspectionRequest, cell::InspectionReply> c(bus, cell::bus::topics::kInspection);
    cell::InspectionRequest r;
    r.op(cell::INSPECTION_STORE_FILE);
    cell::names::Assign(r.file().station(), station, "station");
    cell::names::Assign(r.file().file(), file, "file");
    cell::names::Assign(r.file().text(), text, "text");
    r.file().closed(true);
    auto rep = c.Call(r, cell::bus::Millis(15000));
    cell::bus::ThrowIfError(rep);
  }
  ScopedTempDir tmp_{"cell-inspect-export-"};  // declared first: removed after the writer has stopped
  std::string data_;
  std::unique_ptr<Process> writer_;
};

ins::InspectionFile Sample() {
  ins::InspectionFile f;
  f.header = {"345879", "3452", 14, {2026, 11, 24, 9, 5}};
  f.body = {ins::CentreXY(120, 2.1358, 4., 6.0002), ins::TextLine{"BORE 1"}, ins::TextLine{""},
            ins::Tolerance(130, 'R', 2.1358, 2.135, .0015), ins::Alignment(std::nullopt, 'B', 90.0125)};
  return f;
}

TEST_F(InspectExport, ListsShowsAndExportsAStoredInspectionFile) {
  const std::string text = ins::Format(Sample());
  Store("KT01", "PUMP341", text);
  Store("KT01", "NOTES", "FIRST FILE OPEN.\n");  // an OPF file: no inspection header

  auto ls = Ctl({"inspect", "ls", "KT01/*", "--json"});
  ASSERT_EQ(ls.code, 0) << ls.err;
  auto rows = nlohmann::json::parse(ls.out);
  ASSERT_EQ(rows.size(), 2u) << ls.out;
  EXPECT_EQ(rows[1]["name"], "KT01/PUMP341");
  EXPECT_EQ(rows[1]["kind"], "inspection");
  EXPECT_EQ(rows[1]["size"], static_cast<long>(text.size()));

  auto cat = Ctl({"inspect", "cat", "KT01/PUMP341"});
  ASSERT_EQ(cat.code, 0) << cat.err;
  EXPECT_EQ(cat.out, text);

  auto as_text = Ctl({"inspect", "export", "KT01/PUMP341", "--format", "text"});
  ASSERT_EQ(as_text.code, 0) << as_text.err;
  EXPECT_EQ(as_text.out, text);

  auto csv = Ctl({"inspect", "export", "KT01/PUMP341", "--format", "csv", "--units", "mm"});
  ASSERT_EQ(csv.code, 0) << csv.err;
  EXPECT_EQ(csv.out, ins::ToCsv(Sample(), ins::LinearUnit::kMillimetre));
  EXPECT_NE(csv.out.find("3452,2,130,G24,tolerance,G24 R,2.1358,2.135,0.0015,PASS,mm\r\n"), std::string::npos)
      << csv.out;

  const std::string out = data_ + "/pump.qif";
  auto qif = Ctl({"inspect", "export", "KT01/PUMP341", "--format", "qif", "-o", out});
  ASSERT_EQ(qif.code, 0) << qif.err;
  EXPECT_EQ(qif.out, "");
  EXPECT_EQ(ReadFile(out), ins::ToQif(Sample(), ins::LinearUnit::kInch, "KT01/PUMP341"));

  // Not an inspection file: one line naming the file, line and column; exit 1.
  auto notes = Ctl({"inspect", "export", "KT01/NOTES", "--format", "csv"});
  EXPECT_EQ(notes.code, 1);
  EXPECT_EQ(notes.out, "");
  EXPECT_EQ(notes.err.find("cellctl: KT01/NOTES:1:1: "), 0u) << notes.err;
  EXPECT_NE(notes.err.find("not a KT-APL inspection file"), std::string::npos) << notes.err;
  EXPECT_EQ(std::count(notes.err.begin(), notes.err.end(), '\n'), 1) << notes.err;

  auto bad = Ctl({"inspect", "export", "KT01/PUMP341", "--format", "xml"});
  EXPECT_EQ(bad.code, 2) << bad.err;
  auto missing = Ctl({"inspect", "export", "KT01/NONE", "--format", "qif"});
  EXPECT_EQ(missing.code, 1) << missing.err;
  EXPECT_NE(missing.err.find("KT01/NONE"), std::string::npos) << missing.err;
}

}  // namespace
