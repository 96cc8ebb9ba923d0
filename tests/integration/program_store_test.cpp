// cell-program-store over the bus, driven through cellctl (DESIGN §6 program verbs): every verb, names
// with spaces and ';', bad input (one-line reason, non-zero exit, store unchanged), a 20 MB chunked round
// trip, and the ProgramChange events a subscriber sees.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/error/error.h"
#include "cell/idl/program_store.h"
#include "cell/program_store/client.h"
#include "cell/testing/process.h"

namespace fs = std::filesystem;
using cell::testing::RunCommand;
using cell::testing::RunResult;
using nlohmann::json;

namespace {

const char* kGear =
    "%\n"
    "(NAM,GEAR HOUSING)\n"
    "(UTL,1001,T1002)\n"
    "(UCY,120)\n"
    "N10 G0 X1. Y2. F0\n"
    "N20 M30\n";

// UCY before UTL: stored, with placement warnings.
const char* kMisplaced =
    "%\n"
    "(NAM,BAD HEADING)\n"
    "(UCY,60)\n"
    "(UTL,1001)\n"
    "N10 G0 X1. F0\n"
    "N20 M30\n";

class ProgramStoreTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(cell::testing::MakeTempDir("cell-ps-it-"));
    fs::create_directories(*dir_ + "/data");
    store_ = new cell::testing::Process({cell::testing::BinDir() + "/cell-program-store"},
                                        {{"CELL_DATA_DIR", *dir_ + "/data"}}, *dir_ + "/store.out",
                                        *dir_ + "/store.err");
    // Ready when cellctl gets an answer (bounded; each attempt waits up to 5 s for discovery).
    auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    bool ready = false;
    while (!ready && std::chrono::steady_clock::now() < deadline && store_->Running())
      ready = RunCommand({Ctl(), "program", "ls"}, {}, std::chrono::seconds(10)).code == 0;
    ASSERT_TRUE(ready) << cell::testing::ReadFile(*dir_ + "/store.err");
    bus_ = new cell::bus::Participant("program_store_test");
    changes_ = new cell::bus::Reader<cell::ProgramChange>(
        *bus_, cell::bus::topics::kProgramChange, cell::bus::QosKind::kEvent,
        [](const cell::ProgramChange& c, const cell::bus::SampleInfo&) {
          std::lock_guard lk(events_mu_);
          events_.push_back(c);
        });
    ASSERT_TRUE(changes_->WaitForMatched(1, std::chrono::seconds(10)));
    client_ = new cell::program_store::Client(*bus_, cell::bus::Millis(30000));
  }
  static void TearDownTestSuite() {
    delete client_;
    delete changes_;
    delete bus_;
    delete store_;
    fs::remove_all(*dir_);
    delete dir_;
  }

  static std::string Ctl() { return cell::testing::BinDir() + "/cellctl"; }
  static RunResult Cellctl(std::vector<std::string> args) {
    args.insert(args.begin(), Ctl());
    return RunCommand(args, {}, std::chrono::seconds(60));
  }
  // A cellctl call that must succeed.
  static std::string Ok(const std::vector<std::string>& args) {
    RunResult r = Cellctl(args);
    EXPECT_EQ(r.code, 0) << fmt::format("cellctl {}: {}", fmt::join(args, " "), r.err);
    return r.out;
  }
  static json Ls(const std::string& node, const std::string& pattern = "*") {
    RunResult r = Cellctl({"program", "ls", pattern, "--node", node, "--json"});
    EXPECT_EQ(r.code, 0) << r.err;
    return json::parse(r.out, nullptr, false);
  }
  static std::vector<std::string> Names(const json& ls) {
    std::vector<std::string> out;
    for (auto& f : ls) out.push_back(f["name"]);
    return out;
  }
  std::string Write(const std::string& name, const std::string& content) {
    std::string path = *dir_ + "/" + name;
    std::ofstream(path, std::ios::binary) << content;
    return path;
  }
  // Fails with one line on stderr and a non-zero exit, and changes nothing in any namespace (listed
  // before and after through the test's own client: the same LIST request as `program ls`, without
  // starting six more processes per case).
  void ExpectRefused(const std::vector<std::string>& args, const std::string& reason) {
    std::map<std::string, json> before;
    for (const char* n : {"HOST", "KT01", "KT02", "KT03", "KT04", "OK01"}) before[n] = client_->List(n, "*");
    RunResult r = Cellctl(args);
    std::string what = fmt::format("cellctl {}", fmt::join(args, " "));
    EXPECT_NE(r.code, 0) << what;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << what << ": " << r.err;
    EXPECT_NE(r.err.find(reason), std::string::npos) << what << ": " << r.err;
    for (auto& [n, j] : before) EXPECT_EQ(client_->List(n, "*"), j) << what << " changed " << n;
  }
  static std::vector<cell::ProgramChange> EventsFor(const std::string& node, const std::string& name) {
    std::lock_guard lk(events_mu_);
    std::vector<cell::ProgramChange> out;
    for (auto& e : events_)
      if (e.node() == node && e.name() == name) out.push_back(e);
    return out;
  }

  static std::string* dir_;
  static cell::testing::Process* store_;
  static cell::bus::Participant* bus_;
  static cell::bus::Reader<cell::ProgramChange>* changes_;
  static cell::program_store::Client* client_;
  static std::mutex events_mu_;
  static std::vector<cell::ProgramChange> events_;
};

std::string* ProgramStoreTest::dir_ = nullptr;
cell::testing::Process* ProgramStoreTest::store_ = nullptr;
cell::bus::Participant* ProgramStoreTest::bus_ = nullptr;
cell::bus::Reader<cell::ProgramChange>* ProgramStoreTest::changes_ = nullptr;
cell::program_store::Client* ProgramStoreTest::client_ = nullptr;
std::mutex ProgramStoreTest::events_mu_;
std::vector<cell::ProgramChange> ProgramStoreTest::events_;

TEST_F(ProgramStoreTest, PutNamesFromNamForceRevisionsGetShowAndEvents) {
  std::string f = Write("gear.apl", kGear);
  json put = json::parse(Ok({"program", "put", f, "--json"}));
  EXPECT_EQ(put["name"], "GEAR HOUSING");  // from (NAM,...)
  EXPECT_EQ(put["node"], "HOST");
  EXPECT_EQ(put["revision"], 1);
  EXPECT_EQ(put["dialect"], "ktapl");
  EXPECT_EQ(put["type"], "part_program");

  // Overwrite needs --force; then a new revision, and the old one stays readable.
  ExpectRefused({"program", "put", f}, "already exists");
  std::string v2 = std::string(kGear) + "N30 M30\n";
  json put2 = json::parse(Ok({"program", "put", Write("gear2.apl", v2), "--force", "--json"}));
  EXPECT_EQ(put2["name"], "GEAR HOUSING");
  EXPECT_EQ(put2["revision"], 2);
  EXPECT_EQ(Ok({"program", "get", "GEAR HOUSING"}), v2);
  EXPECT_EQ(Ok({"program", "get", "GEAR HOUSING", "--revision", "1"}), kGear);
  std::string out = *dir_ + "/got.apl";
  Ok({"program", "get", "GEAR HOUSING", "--revision", "1", "-o", out});
  EXPECT_EQ(cell::testing::ReadFile(out), kGear);

  json show = json::parse(Ok({"program", "show", "GEAR HOUSING", "--json"}));
  EXPECT_EQ(show["nam"], "GEAR HOUSING");
  EXPECT_EQ(show["utl"], json({"1001", "1002"}));
  EXPECT_EQ(show["ucy_s"], 120);
  ASSERT_EQ(show["revisions"].size(), 2u);
  EXPECT_EQ(show["revisions"][0]["revision"], 1);
  EXPECT_EQ(show["revisions"][1]["size"], v2.size());

  // --name overrides NAM; a name with spaces and ';' in a station namespace.
  Write("fixture.txt", "(FXC,H1 I0 X-.0012 Y.0030)\n");
  json fxt = json::parse(
      Ok({"program", "put", *dir_ + "/fixture.txt", "--name", "PALLET38;FXT", "--node", "KT01", "--json"}));
  EXPECT_EQ(fxt["name"], "PALLET38;FXT");
  EXPECT_EQ(fxt["type"], "fixture_offsets");
  EXPECT_EQ(Ok({"program", "get", "PALLET38;FXT", "--node", "KT01"}), "(FXC,H1 I0 X-.0012 Y.0030)\n");
  Ok({"program", "put", f, "--name", "SPACED NAME 1"});
  EXPECT_EQ(Ok({"program", "get", "SPACED NAME 1"}), kGear);

  // Created, updated (revision 2), deleted: on the ProgramChange topic with their revisions.
  Ok({"program", "rm", "SPACED NAME 1"});
  auto seen = [&](const std::string& node, const std::string& name, size_t n) {
    return cell::bus::WaitUntil([&] { return EventsFor(node, name).size() >= n; }, std::chrono::seconds(5));
  };
  ASSERT_TRUE(seen("HOST", "GEAR HOUSING", 2));
  auto g = EventsFor("HOST", "GEAR HOUSING");
  EXPECT_EQ(g[0].kind(), cell::CHANGE_CREATED);
  EXPECT_EQ(g[0].revision(), 1u);
  EXPECT_EQ(g[1].kind(), cell::CHANGE_UPDATED);
  EXPECT_EQ(g[1].revision(), 2u);
  EXPECT_LT(g[0].seq(), g[1].seq());
  ASSERT_TRUE(seen("HOST", "SPACED NAME 1", 2));
  auto s = EventsFor("HOST", "SPACED NAME 1");
  EXPECT_EQ(s[0].kind(), cell::CHANGE_CREATED);
  EXPECT_EQ(s[1].kind(), cell::CHANGE_DELETED);
  EXPECT_EQ(s[1].revision(), 1u);
  ASSERT_TRUE(seen("KT01", "PALLET38;FXT", 1));
  EXPECT_EQ(EventsFor("KT01", "PALLET38;FXT")[0].kind(), cell::CHANGE_CREATED);
}

TEST_F(ProgramStoreTest, MisplacedUtlUcyIsStoredWithWarningsOnStderr) {
  RunResult r = Cellctl({"program", "put", Write("misplaced.apl", kMisplaced), "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("UTL"), std::string::npos) << r.err;
  json j = json::parse(r.out);
  EXPECT_EQ(j["name"], "BAD HEADING");
  EXPECT_FALSE(j["warnings"].empty());
  EXPECT_EQ(j["revision"], 1);
}

TEST_F(ProgramStoreTest, ListWildcards) {
  for (std::string n : {"WC PART1", "WC PART2", "WC PART10", "WC BOX"})
    Ok({"program", "put", Write("wc.apl", kGear), "--name", n, "--node", "KT04"});
  EXPECT_EQ(Names(Ls("KT04", "WC PART?")), (std::vector<std::string>{"WC PART1", "WC PART2"}));
  EXPECT_EQ(Names(Ls("KT04", "WC PART*")), (std::vector<std::string>{"WC PART1", "WC PART10", "WC PART2"}));
  EXPECT_EQ(Names(Ls("KT04", "*BOX")), (std::vector<std::string>{"WC BOX"}));
  EXPECT_EQ(Names(Ls("KT04", "W?*1?")), (std::vector<std::string>{"WC PART10"}));
  EXPECT_TRUE(Ls("KT04", "NOTHING*").empty());
  json all = Ls("KT04");
  ASSERT_EQ(all.size(), 4u);
  for (const char* key : {"name", "node", "type", "dialect", "revision", "size", "protected"})
    EXPECT_TRUE(all[0].contains(key)) << key;
  // The table form too.
  std::string table = Ok({"program", "ls", "WC B*", "--node", "KT04"});
  EXPECT_NE(table.find("WC BOX"), std::string::npos);
}

// `program ls` pages (DESIGN §6, issue 39 item 2): 520 files with 32-character names (the KT-APL limit) are
// more than one 64 KiB reply; the client and cellctl follow the cursor by name, and --limit/--after take the
// same slice of the whole.
TEST_F(ProgramStoreTest, ListPagesThroughANamespaceLargerThanAReply) {
  cell::program_store::Client::PutOptions po;
  po.node = "KT04";
  for (int i = 0; i < 520; ++i) client_->Put(fmt::format("PAGE{:03} {}", i, std::string(24, 'L')), kGear, po);
  json all = client_->List("KT04", "PAGE*");
  ASSERT_EQ(all.size(), 520u);
  EXPECT_GT(all.dump().size(), 65536u);
  for (size_t i = 1; i < all.size(); ++i) ASSERT_LT(all[i - 1]["name"], all[i]["name"]);
  EXPECT_EQ(Ls("KT04", "PAGE*"), all);  // cellctl: the default --limit 1000 holds them all
  const std::string after = all[299]["name"].get<std::string>();
  RunResult r =
      Cellctl({"program", "ls", "PAGE*", "--node", "KT04", "--json", "--limit", "220", "--after", after});
  ASSERT_EQ(r.code, 0) << r.err;
  json slice = json::parse(r.out);
  ASSERT_EQ(slice.size(), 220u);
  EXPECT_EQ(slice.front(), all[300]);
  EXPECT_EQ(slice.back(), all[519]);
  EXPECT_TRUE(client_->List("KT04", "PAGE*", 0, all[519]["name"].get<std::string>()).empty());
  EXPECT_EQ(client_->List("KT04", "PAGE*", 3).size(), 3u);
}

TEST_F(ProgramStoreTest, CopyAndMoveBetweenNamespacesThenRemove) {
  Ok({"program", "put", Write("rcp.apl", kGear), "--name", "RCP PART"});
  // KT-APL RCP: HOST -> station, station -> station, back to HOST under another name.
  Ok({"program", "cp", "RCP PART", "--from", "HOST", "--to", "KT02"});
  EXPECT_EQ(Names(Ls("KT02", "RCP*")), std::vector<std::string>{"RCP PART"});
  EXPECT_EQ(Ok({"program", "get", "RCP PART", "--node", "KT02"}), kGear);
  ExpectRefused({"program", "cp", "RCP PART", "--from", "HOST", "--to", "KT02"}, "already exists");
  Ok({"program", "cp", "RCP PART", "--from", "HOST", "--to", "KT02", "--force"});
  EXPECT_EQ(Ls("KT02", "RCP PART")[0]["revision"], 2);

  Ok({"program", "mv", "RCP PART", "RCP MOVED", "--from", "KT02", "--to", "KT03"});
  EXPECT_TRUE(Ls("KT02", "RCP*").empty());
  json moved = Ls("KT03", "RCP*");
  ASSERT_EQ(moved.size(), 1u);
  EXPECT_EQ(moved[0]["name"], "RCP MOVED");
  EXPECT_EQ(moved[0]["revision"], 2);  // history kept
  Ok({"program", "cp", "RCP MOVED", "RCP BACK", "--from", "KT03", "--to", "HOST"});
  EXPECT_EQ(Ok({"program", "get", "RCP BACK"}), kGear);

  Ok({"program", "rm", "RCP MOVED", "--node", "KT03"});
  EXPECT_TRUE(Ls("KT03", "RCP*").empty());
  ExpectRefused({"program", "rm", "RCP MOVED", "--node", "KT03"}, "RCP MOVED");
  ASSERT_TRUE(cell::bus::WaitUntil([&] { return EventsFor("KT03", "RCP MOVED").size() >= 2; },
                                   std::chrono::seconds(5)));
  EXPECT_EQ(EventsFor("KT03", "RCP MOVED").back().kind(), cell::CHANGE_DELETED);
}

// docs/security.md: the store knows each request's sender (its partition; authenticated under DDS
// Security, claimed here) and logs every change with it. A station changes its own namespace, sends HOST a
// data file (KT-APL RCP TO HOST, ln 8316-8356), and changes nothing else.
TEST_F(ProgramStoreTest, AStationChangesOnlyItsOwnNamespaceAndTheAuditNamesWhoChangedWhat) {
  cell::bus::ParticipantOptions o = cell::bus::Named("program_store_test/kt02");
  o.identity = "interpreter-KT02";
  cell::bus::Participant station(o);
  cell::program_store::Client kt02(station, cell::bus::Millis(30000));
  auto put = [&](const std::string& node, const std::string& name, const std::string& type) {
    cell::program_store::Client::PutOptions po;
    po.node = node;
    po.file_type = type;
    return kt02.Put(name, kGear, po);
  };
  EXPECT_NO_THROW(put("KT02", "OWN PART", ""));
  EXPECT_NO_THROW(put("HOST", "KT02 GAUGE.TXT", "data"));
  for (const auto& [node, name, type] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"KT01", "FORGED PART", ""}, {"HOST", "FORGED PART", ""}}) {
    try {
      put(node, name, type);
      ADD_FAILURE() << "interpreter-KT02 changed " << node;
    } catch (const cell::Error& e) {
      EXPECT_EQ(e.code(), cell::Errc::kPermissionDenied) << e.what();
      EXPECT_NE(std::string(e.what()).find("interpreter-KT02"), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(Ls("KT01", "FORGED*").empty());
  EXPECT_TRUE(Ls("HOST", "FORGED*").empty());
  // The control: the operator's CLI (a cell identity) writes into KT01.
  Ok({"program", "put", Write("kt01.apl", kGear), "--name", "OPERATOR PART", "--node", "KT01"});
  EXPECT_EQ(Names(Ls("KT01", "OPERATOR*")), std::vector<std::string>{"OPERATOR PART"});
  // The audit trail, in the store's journal (stderr here).
  ASSERT_TRUE(cell::bus::WaitUntil(
      [&] {
        const std::string err = cell::testing::ReadFile(*dir_ + "/store.err");
        return err.find("accepted program put KT02:OWN PART from identity 'interpreter-KT02'") !=
                   std::string::npos &&
               err.find("accepted program put KT01:OPERATOR PART from identity 'operator'") !=
                   std::string::npos;
      },
      std::chrono::seconds(5)))
      << cell::testing::ReadFile(*dir_ + "/store.err");
}

// What a read-only viewer lists (docs/security.md): the store publishes its list on cell/program/list, the
// same files as `program ls` gets by request, kept up to date by puts, flags and deletes.
TEST_F(ProgramStoreTest, TheListIsPublishedForViewers) {
  auto names = [](const json& list) {
    std::vector<std::string> out;
    for (auto& f : list) out.push_back(f["name"].get<std::string>());
    return out;
  };
  Ok({"program", "put", Write("pub1.apl", kGear), "--name", "PUB ONE", "--node", "KT04"});
  Ok({"program", "put", Write("pub2.apl", kGear), "--name", "PUB TWO", "--node", "KT04"});
  Ok({"program", "protect", "PUB TWO", "--node", "KT04"});
  const cell::bus::Millis wait(10000);
  json published = cell::program_store::ListPublished(*bus_, "KT04", "PUB*", wait);
  EXPECT_EQ(names(published), names(Ls("KT04", "PUB*")));  // the control: the request's answer
  EXPECT_EQ(names(published), (std::vector<std::string>{"PUB ONE", "PUB TWO"}));
  ASSERT_EQ(published.size(), 2u);
  EXPECT_EQ(published[1]["protected"], true);
  EXPECT_EQ(published[0]["revision"], 1);
  Ok({"program", "rm", "PUB ONE", "--node", "KT04"});
  // A fresh reader (a viewer starting now) sees the namespace as it is.
  cell::bus::Participant viewer("program_store_test/viewer");
  EXPECT_EQ(names(cell::program_store::ListPublished(viewer, "KT04", "PUB*", wait)),
            std::vector<std::string>{"PUB TWO"});
  EXPECT_TRUE(cell::program_store::ListPublished(viewer, "KT04", "NONE*", wait).empty());
}

TEST_F(ProgramStoreTest, ProtectedFilesCannotBeOverwrittenMovedOrDeleted) {
  std::string f = Write("prot.apl", kGear);
  Ok({"program", "put", f, "--name", "KEEP ME"});
  Ok({"program", "protect", "KEEP ME"});
  EXPECT_EQ(Ls("HOST", "KEEP ME")[0]["protected"], true);
  ExpectRefused({"program", "put", f, "--name", "KEEP ME", "--force"}, "protected");
  ExpectRefused({"program", "rm", "KEEP ME"}, "protected");
  ExpectRefused({"program", "mv", "KEEP ME", "KEEP YOU"}, "protected");
  Ok({"program", "cp", "KEEP ME", "--to", "KT01"});  // reading and copying from it is fine
  Ok({"program", "unprotect", "KEEP ME"});
  EXPECT_EQ(Ls("HOST", "KEEP ME")[0]["protected"], false);
  Ok({"program", "put", f, "--name", "KEEP ME", "--force"});
  Ok({"program", "rm", "KEEP ME"});
  EXPECT_TRUE(Ls("HOST", "KEEP ME").empty());
}

TEST_F(ProgramStoreTest, ImportAndExportDirectories) {
  std::string in = *dir_ + "/import", out = *dir_ + "/export";
  fs::create_directories(in);
  std::map<std::string, std::string> files = {
      {"a.apl", kGear},                            // stored as its NAM
      {"PALLET12;FXT", "(FXC,H2 X0)\n"},           // ';' in a file name
      {"O1000.MIN", "O1000\nG0 X10. Z5.\nM02\n"},  // Okuma by content in an OK01 namespace
  };
  for (auto& [n, c] : files) std::ofstream(in + "/" + n, std::ios::binary) << c;
  std::string log = Ok({"program", "import", in, "--node", "OK01"});
  EXPECT_NE(log.find("3 file(s) imported"), std::string::npos) << log;
  EXPECT_EQ(Names(Ls("OK01")), (std::vector<std::string>{"GEAR HOUSING", "O1000.MIN", "PALLET12;FXT"}));
  log = Ok({"program", "export", out, "--node", "OK01"});
  EXPECT_NE(log.find("3 file(s) exported"), std::string::npos) << log;
  EXPECT_EQ(cell::testing::ReadFile(out + "/GEAR HOUSING"), kGear);
  EXPECT_EQ(cell::testing::ReadFile(out + "/PALLET12;FXT"), files["PALLET12;FXT"]);
  EXPECT_EQ(cell::testing::ReadFile(out + "/O1000.MIN"), files["O1000.MIN"]);
}

// A refused file does not stop an import: each refusal is one line naming the file, the others are stored,
// and the exit status says something was refused.
TEST_F(ProgramStoreTest, ImportReportsRefusedFilesAndStoresTheRest) {
  std::string in = *dir_ + "/import-mixed";
  fs::create_directories(in);
  std::ofstream(in + "/a.apl", std::ios::binary) << kGear;
  std::ofstream(in + "/b.bin", std::ios::binary) << std::string("AB\0CD\n", 6);  // not text
  std::ofstream(in + "/c.txt", std::ios::binary) << "G0 X1.\n";
  RunResult r = Cellctl({"program", "import", in, "--node", "KT03"});
  EXPECT_EQ(r.code, 1) << r.out << r.err;
  EXPECT_NE(r.out.find("2 file(s) imported"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("b.bin: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("not text"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("1 file(s) refused"), std::string::npos) << r.err;
  EXPECT_EQ(Names(Ls("KT03")), (std::vector<std::string>{"GEAR HOUSING", "c.txt"}));
}

TEST_F(ProgramStoreTest, BadInputIsRefusedWithOneLineAndChangesNothing) {
  std::string f = Write("bad.apl", kGear);
  ExpectRefused({"program", "put", f, "--name", ""}, "empty");
  ExpectRefused({"program", "put", f, "--name", std::string(33, 'A')}, "32");    // KT-APL limit
  ExpectRefused({"program", "put", f, "--name", std::string(129, 'A')}, "128");  // the wire bound
  ExpectRefused({"program", "put", f, "--name", "A*B"}, "*");
  ExpectRefused({"program", "put", f, "--name", "A/B"}, "/");
  ExpectRefused({"program", "put", f, "--name", "A,B"}, ",");
  ExpectRefused({"program", "put", Write("bin.dat", std::string("AB\0CD\n", 6)), "--name", "BIN"},
                "not text");
  ExpectRefused({"program", "put", f, "--node", "KT99"}, "KT99");
  ExpectRefused({"program", "get", "GEAR HOUSING", "--node", "KT99"}, "KT99");
  ExpectRefused({"program", "ls", "--node", "KT99"}, "KT99");
  ExpectRefused({"program", "get", "NO SUCH PROGRAM"}, "NO SUCH PROGRAM");
  ExpectRefused({"program", "put", *dir_ + "/missing-file.apl"}, "missing-file.apl");
  // Overwrite without --force, of a name that exists.
  Ok({"program", "put", f, "--name", "EXISTS"});
  ExpectRefused({"program", "put", f, "--name", "EXISTS"}, "--force");
}

// `program plot` (docs/plot.md) fetches a stored program, runs it through its dialect offline and draws it:
// a turned corpus program in the lathe's half-section, from HOST by its dialect and from a station's
// namespace with --station; a milled one in plan and elevation. Every arc op of the hand-derived expectation
// is one arc element per view (the first motion op, not an arc in either, only says where the path starts).
TEST_F(ProgramStoreTest, PlotDrawsAStoredProgramInItsMachinesView) {
  const std::string corpus = cell::testing::SourceDir() + "/tests/conformance/";
  auto arcs = [&](const std::string& expected) {
    int n = 0;
    for (std::istringstream in(cell::testing::ReadFile(corpus + expected)); !in.eof();) {
      std::string line;
      std::getline(in, line);
      n += line.find("\"op\":\"arc\"") != std::string::npos;
    }
    return n;
  };
  auto count = [](const std::string& text, const std::string& what) {
    int n = 0;
    for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  const std::string turned = corpus + "okuma/p8_lap_copy_turning_g86.okuma";
  Ok({"program", "put", turned, "--name", "LAP.MIN", "--dialect", "okuma"});
  Ok({"program", "put", turned, "--name", "LAP.MIN", "--dialect", "okuma", "--node", "OK01"});
  Ok({"program", "put", corpus + "balt/gtl_example_4.balt", "--name", "GTL4", "--dialect", "balt"});
  const std::string svg = *dir_ + "/plot.svg";

  Ok({"program", "plot", "LAP.MIN", "-o", svg});
  std::string page = cell::testing::ReadFile(svg);
  EXPECT_EQ(count(page, "data-view=\"half-section\""), 1);
  EXPECT_EQ(count(page, "<path class=\"arc\""), arcs("okuma/p8_lap_copy_turning_g86.expected"));
  EXPECT_NE(page.find("LAP.MIN (okuma, HOST)"), std::string::npos);

  Ok({"program", "plot", "LAP.MIN", "--station", "OK01", "-o", svg});
  page = cell::testing::ReadFile(svg);
  EXPECT_NE(page.find("LAP.MIN (okuma, OK01, station OK01)"), std::string::npos);
  EXPECT_EQ(count(page, "<path class=\"arc\""), arcs("okuma/p8_lap_copy_turning_g86.expected"));

  Ok({"program", "plot", "GTL4", "-o", svg});
  page = cell::testing::ReadFile(svg);
  EXPECT_EQ(count(page, "<g class=\"view\""), 2);
  EXPECT_EQ(count(page, "<path class=\"arc\""), 2 * arcs("balt/gtl_example_4.expected"));
  EXPECT_EQ(RunCommand({"xmllint", "--noout", "--nonet", svg}).code, 0);

  ExpectRefused({"program", "plot", "NO SUCH", "-o", svg}, "NO SUCH");
  Ok({"program", "put", Write("notes.txt", "just words\n"), "--name", "NOTES", "--type", "data"});
  ExpectRefused({"program", "plot", "NOTES", "-o", svg}, "no dialect");
  fs::remove(svg);
}

TEST_F(ProgramStoreTest, TwentyMegabytesRoundTripInChunks) {
  std::string big;
  big.reserve(20 << 20);
  for (int i = 0; big.size() < (20u << 20); ++i)
    big += fmt::format("row {:08d} of the big data file: 0123456789 abcdefghijklmnopqrstuvwxyz\n", i);
  std::string in = Write("big.txt", big), out = *dir_ + "/big.out";
  auto t0 = std::chrono::steady_clock::now();
  json put = json::parse(Ok({"program", "put", in, "--name", "BIG DATA", "--json"}));
  auto t1 = std::chrono::steady_clock::now();
  EXPECT_EQ(put["size"], big.size());
  EXPECT_EQ(put["type"], "data");
  Ok({"program", "get", "BIG DATA", "-o", out});
  auto t2 = std::chrono::steady_clock::now();
  std::string back = cell::testing::ReadFile(out);
  EXPECT_EQ(back.size(), big.size());
  EXPECT_TRUE(back == big);
  using ms = std::chrono::milliseconds;
  std::printf("20 MB via cellctl: put %lld ms, get %lld ms\n",
              static_cast<long long>(std::chrono::duration_cast<ms>(t1 - t0).count()),
              static_cast<long long>(std::chrono::duration_cast<ms>(t2 - t1).count()));
  fs::remove(in);
  fs::remove(out);
}

}  // namespace
