#include "cell/tooltable/tooltable.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cell/error/error.h"
#include "cell/tooltable/wire.h"

namespace cell::tooltable {
namespace {

TEST(ToolNumber, Normalize) {
  EXPECT_EQ(NormalizeToolNumber("T0012"), "12");
  EXPECT_EQ(NormalizeToolNumber("1234567"), "1234567");
  EXPECT_EQ(NormalizeToolNumber("33412.5"), "33412.5");
  EXPECT_EQ(NormalizeToolNumber("t7.0"), "7");
  EXPECT_THROW(NormalizeToolNumber("12345678"), Error);
  EXPECT_THROW(NormalizeToolNumber("T"), Error);
  EXPECT_THROW(NormalizeToolNumber("12A"), Error);
  EXPECT_EQ(BaseTool("33412.5"), "33412");
}

TEST(ToolTable, UpsertReplacesTheWholeDataSet) {
  ToolTable t({ToolEntry{.tool = "1", .socket = 1, .length = 50, .worn = true}});
  t.Upsert(ToolEntry{.tool = "1", .socket = 1, .length = 60});
  t.Upsert(ToolEntry{.tool = "2", .socket = 2, .length = 70});
  ASSERT_EQ(t.entries().size(), 2u);
  EXPECT_DOUBLE_EQ(t.Find("1")->length, 60);
  EXPECT_FALSE(t.Find("1")->worn);  // a new data set: a freshly preset tool
  EXPECT_EQ(t.Find("2")->socket, 2);
  EXPECT_TRUE(t.Holds("2"));
  EXPECT_FALSE(t.Holds("3"));
}

TEST(ToolTable, SuffixSetHoldsBaseToolButBrokenDoesNot) {
  ToolTable t(
      {ToolEntry{.tool = "33412.5", .socket = 1}, ToolEntry{.tool = "9", .socket = 2, .broken = true}});
  EXPECT_TRUE(t.Holds("33412"));
  EXPECT_TRUE(t.Holds("33412.5"));
  EXPECT_FALSE(t.Holds("33412.4"));
  EXPECT_FALSE(t.Holds("9"));
}

// Part 2 Fig. 6.1 (ln 6213-6222) lists tools 4421 and 11113 twice: a data set of a tool number already in
// another magazine socket is an alternate (sister) tool, kept beside it; the same socket replaces.
TEST(ToolTable, AnotherSocketAddsAnAlternateTheSameSocketReplaces) {
  ToolTable t;
  t.Upsert(ToolEntry{.tool = "4421", .socket = 3, .length = 100, .life_left_min = 200});
  t.Upsert(ToolEntry{.tool = "4421", .socket = 17, .length = 101, .life_left_min = 200});
  ASSERT_EQ(t.entries().size(), 2u);
  t.Upsert(ToolEntry{.tool = "4421", .socket = 17, .length = 102, .life_left_min = 200});
  ASSERT_EQ(t.entries().size(), 2u);
  EXPECT_DOUBLE_EQ(t.Find("4421", 17)->length, 102);
  EXPECT_DOUBLE_EQ(t.Find("4421")->length, 100);  // the first in table order
  EXPECT_EQ(t.Find("4421", 9), nullptr);
  // A manual tool (no socket) of the number replaces its data set rather than adding a third.
  t.Upsert(ToolEntry{.tool = "5", .socket = 0, .length = 1});
  t.Upsert(ToolEntry{.tool = "5", .socket = 0, .length = 2});
  EXPECT_EQ(t.entries().size(), 3u);
  EXPECT_DOUBLE_EQ(t.Find("5")->length, 2);
}

// Tool life (part 1 TLD L, ln 4007; part 2 Fig. 6.1: cutting time past the limit marks the tool worn):
// cutting time is charged to the data set that cut; at zero life it is worn, and selection moves on to the
// alternate; with every data set worn or broken the number is not held (the UTL check) and not selectable.
TEST(ToolTable, CuttingTimeWearsTheToolAndSelectionMovesToTheAlternate) {
  ToolTable t({ToolEntry{.tool = "1001", .socket = 1, .life_left_min = 1.0},
               ToolEntry{.tool = "1001", .socket = 2, .life_left_min = 2.0},
               ToolEntry{.tool = "2002", .socket = 3}});
  bool exists = false;
  ASSERT_EQ(t.Select("1001", &exists), t.Find("1001", 1));
  EXPECT_TRUE(exists);
  ASSERT_TRUE(t.Charge(ToolWear{"1001", 1, 45.0, false}));
  EXPECT_NEAR(t.Find("1001", 1)->life_left_min, 0.25, 1e-12);
  EXPECT_FALSE(t.Find("1001", 1)->worn);
  EXPECT_EQ(t.Select("1001"), t.Find("1001", 1));
  ASSERT_TRUE(t.Charge(ToolWear{"1001", 1, 20.0, false}));  // 65 s in all: past its minute
  EXPECT_EQ(t.Find("1001", 1)->life_left_min, 0);
  EXPECT_TRUE(t.Find("1001", 1)->worn);
  EXPECT_EQ(t.Select("1001"), t.Find("1001", 2));
  EXPECT_DOUBLE_EQ(t.Find("1001", 2)->life_left_min, 2.0);  // the alternate is untouched
  EXPECT_TRUE(t.Holds("1001"));
  ASSERT_TRUE(t.Charge(ToolWear{"1001", 2, 0, true}));  // G38 found it broken
  EXPECT_TRUE(t.Find("1001", 2)->broken);
  EXPECT_EQ(t.Select("1001", &exists), nullptr);
  EXPECT_TRUE(exists);
  EXPECT_FALSE(t.Holds("1001"));
  // No life given (0): cutting time does not wear it; a number not in the table is not selected.
  ASSERT_TRUE(t.Charge(ToolWear{"2002", 3, 3600.0, false}));
  EXPECT_FALSE(t.Find("2002")->worn);
  EXPECT_EQ(t.Select("7777", &exists), nullptr);
  EXPECT_FALSE(exists);
  EXPECT_FALSE(t.Charge(ToolWear{"7777", 0, 1.0, false}));
  // A socket the table does not know charges the number's first data set (the machine found it by number).
  ToolTable u({ToolEntry{.tool = "9", .socket = 4, .life_left_min = 10}});
  ASSERT_TRUE(u.Charge(ToolWear{"9", 0, 60.0, false}));
  EXPECT_DOUBLE_EQ(u.Find("9")->life_left_min, 9.0);
}

TEST(ToolTable, WornToolIsNotHeld) {
  ToolTable t({ToolEntry{.tool = "33412", .socket = 1, .worn = true},
               ToolEntry{.tool = "33412.5", .socket = 1, .worn = true}});
  EXPECT_FALSE(t.Holds("33412"));
  t.Upsert(ToolEntry{.tool = "33412", .socket = 6});
  EXPECT_TRUE(t.Holds("33412"));
}

// KT-APL manual ln 4073: a process compensation needs its tool's data set first; ln 4093-4095: it is added
// to the data set while its pallet is on the table.
TEST(ToolTable, ProcessCompensationNeedsDataSetAndAddsOnItsPallet) {
  ToolTable t;
  EXPECT_FALSE(t.UpsertProcess(ProcessComp{"5", 3, 0.1, 0}));
  EXPECT_TRUE(t.process_comps().empty());
  t.Upsert(ToolEntry{.tool = "5", .socket = 1, .length = 100, .diameter = 10});
  EXPECT_TRUE(t.UpsertProcess(ProcessComp{"5", 3, 0.1, -0.2}));
  EXPECT_TRUE(t.UpsertProcess(ProcessComp{"5", 3, 0.2, -0.4}));
  ASSERT_EQ(t.process_comps().size(), 1u);
  ToolTable::Compensation c;
  ASSERT_TRUE(t.Effective("5", 3, &c));
  EXPECT_DOUBLE_EQ(c.length, 100.2);
  EXPECT_DOUBLE_EQ(c.diameter, 9.6);
  ASSERT_TRUE(t.Effective("5", 4, &c));
  EXPECT_DOUBLE_EQ(c.length, 100);
  EXPECT_FALSE(t.Effective("6", 0, &c));
  t.Clear();
  EXPECT_TRUE(t.entries().empty());
  EXPECT_TRUE(t.process_comps().empty());
}

ToolTable EveryField() {
  ToolTable t(
      {ToolEntry{.tool = "33412",
                 .socket = 12,
                 .length = 0.02,
                 .diameter = -0.25,  // signed, KT-APL manual example E45
                 .life_left_min = 225,
                 .worn = true,
                 .check = true,
                 .max_hp = 5.9},
       ToolEntry{.tool = "3", .socket = 3, .x_offset = -1.5, .z_offset = 2.25, .nose_radius = 0.4, .tip = 3},
       ToolEntry{.tool = "7", .socket = 7, .length = 80, .diameter = 12, .length_axis = 'X'}});
  t.UpsertProcess(ProcessComp{"33412", 12, 0.0003, -0.0004});
  return t;
}

TEST(ToolTable, JsonRoundTripKeepsEveryField) {
  ToolTable t = EveryField();
  EXPECT_EQ(FromJson(ToJson(t)), t);
  nlohmann::json kt = EntryJson(t.entries()[0]);
  for (const char* k : {"tool", "socket", "length", "diameter", "life_left_min", "worn", "broken"}) {
    EXPECT_TRUE(kt.contains(k)) << k;  // DESIGN §6 keys
  }
  EXPECT_FALSE(kt.contains("nose_radius"));  // lathe keys only where they apply
  EXPECT_TRUE(EntryJson(t.entries()[1]).contains("nose_radius"));
  EXPECT_EQ(EntryJson(t.entries()[2]).at("length_axis"), "X");
  EXPECT_THROW(FromJson(nlohmann::json::parse(R"({"entries":[{"socket":1}]})")), Error);
}

TEST(ToolTable, WireRoundTripKeepsEveryField) {
  ToolTable t = EveryField();
  cell::ToolTable w = ToWire(t, "KT01", 7);
  EXPECT_EQ(w.station(), "KT01");
  EXPECT_EQ(w.revision(), 7u);
  EXPECT_EQ(FromWire(w), t);
  ToolTable bad({ToolEntry{.tool = std::string(17, '1')}});
  EXPECT_THROW(ToWire(bad, "KT01", 1), Error);
}

}  // namespace
}  // namespace cell::tooltable
