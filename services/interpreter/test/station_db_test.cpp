// Station databases made by earlier releases open and migrate. fixtures/interpreter-KT01-v2.db was written by
// the release before issue 12 (schema 2; fixtures/make-v2-fixture.sh says how): KT01's config tools plus a
// TLD load, L1500 = 7 and V5 = 3 set from cellctl, input I3 = 1, two completed runs (the second's record
// still in the outbox: the inspection writer was killed), a third run ACTIVE when the interpreter was killed,
// the panel held at 50 % feed override.
#include <gtest/gtest.h>

#include <filesystem>

#include "cell/store/sqlite.h"
#include "harness.h"

namespace cell::station::testing {
namespace {

class StationDbFixture : public StationHarness {
 protected:
  void SetUp() override {
    StationHarness::SetUp();
    station_.reset();
    std::filesystem::remove(db());
    std::filesystem::copy_file(std::string(STATION_FIXTURES) + "/interpreter-KT01-v2.db", db());
  }
};

TEST_F(StationDbFixture, AVersion2DatabaseMigratesWithEverythingItHeld) {
  {
    StationDb raw(db());
    EXPECT_EQ(raw.SchemaVersion(), 4);
    // The old release's input name stays as it was (no KT-APL word of its own); version 4 adds outputs.
    EXPECT_EQ(raw.LoadInputs(), (std::map<std::string, double>{{"I3", 1.0}}));
    EXPECT_TRUE(raw.LoadOutputs().empty());
    EXPECT_EQ(raw.Count(RunState::kCompleted), 2);
    EXPECT_EQ(raw.Count(RunState::kActive), 1);
    EXPECT_EQ(raw.LoadPanel(), (PanelState{true, 0.5, 1.0, {}, std::nullopt}));
    EXPECT_TRUE(raw.ToolsSeeded());
  }
  Make();  // the station core on it
  auto mem = station_->MemoryState().image;
  EXPECT_EQ(mem.variables, (std::map<std::string, double>{{"L1500", 7.0}, {"V5", 3.0}}));  // I3 is an input
  std::vector<std::string> tools;
  for (const auto& e : mem.tools.entries()) tools.push_back(e.tool);
  EXPECT_EQ(tools, (std::vector<std::string>{"1001", "1002", "1003", "1004", "3001", "33412.5", "7001"}));
  const auto* t = mem.tools.Find("7001");
  ASSERT_NE(t, nullptr);
  EXPECT_EQ(t->socket, 9);
  EXPECT_DOUBLE_EQ(t->length, 80.0);
  EXPECT_DOUBLE_EQ(mem.tools.Find("33412.5")->diameter, -6.35);
  EXPECT_EQ(mem.tools.Find("1001")->life_left_min, 240);
  EXPECT_TRUE(station_->Control().feed_hold());
  EXPECT_DOUBLE_EQ(station_->Control().feed_override(), 0.5);

  // The run that was ACTIVE when the old process died is reported failed; its successor's queue is empty.
  station_->Recover();
  ASSERT_TRUE(io_.LastRun(3));
  EXPECT_EQ(io_.LastRun(3)->state(), cell::RUN_FAILED);
  EXPECT_FALSE(station_->RunNext());
  // The record the old process could not hand over goes now, and the failed run's own (one per dispatch).
  station_->FlushOutbox();
  ASSERT_EQ(io_.records.size(), 2u);
  EXPECT_EQ(io_.records[0].run().dispatch_id(), 2);
  EXPECT_TRUE(io_.records[0].run().completed());
  EXPECT_EQ(io_.records[1].run().dispatch_id(), 3);
  EXPECT_FALSE(io_.records[1].run().completed());
  // A re-sent old dispatch is recognised.
  EXPECT_EQ(Dispatch(1, {"P"}).state(), cell::RUN_COMPLETED);
  // Programs run on it, starting from the migrated memory.
  Command(cell::STATION_CYCLE_START);
  Put("USE", "G71\nT7001 M06\nG90 G01 XL1500 Y0 Z100. F0\nM30\n");
  Dispatch(4, {"USE"});
  ASSERT_EQ(RunOne(4).state(), cell::RUN_COMPLETED);
  auto moves = servo_.Ran(4, cell::SEGMENT_RAPID);
  ASSERT_FALSE(moves.empty());
  EXPECT_NEAR(moves.back().target()[0], 7.0, 1e-9);
  EXPECT_NEAR(moves.back().target()[2], 180.0, 1e-9);
}

TEST_F(StationDbFixture, ANewerDatabaseIsRefused) {
  {
    auto raw = store::Database::Open(db());
    raw.Exec("INSERT INTO schema_version(version, description) VALUES(99, 'future')");
  }
  EXPECT_THROW(StationDb{db()}, Error);
}

TEST(StationDbMigrations, AreNumberedFromOne) {
  auto m = StationDb::Migrations();
  for (size_t i = 0; i < m.size(); ++i) EXPECT_EQ(m[i].version, static_cast<int>(i) + 1);
}

}  // namespace
}  // namespace cell::station::testing
