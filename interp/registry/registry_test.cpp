// The one table of dialects: names and aliases, what each dialect says about files, and runs by name.
#include "cell/interp/interp.h"

#include <gtest/gtest.h>

#include <set>

#include "cell/error/error.h"

namespace cell::interp {
namespace {

TEST(Registry, FourDialectsByNameAndAlias) {
  std::vector<std::string> names;
  for (const Dialect* d : Dialects()) names.emplace_back(d->name());
  EXPECT_EQ(names, (std::vector<std::string>{"ktapl", "okuma", "emco", "balt"}));
  EXPECT_EQ(FindDialect("KT-APL"), FindDialect("ktapl"));
  EXPECT_EQ(FindDialect("osp")->name(), "okuma");
  EXPECT_EQ(FindDialect("TM02")->name(), "emco");
  EXPECT_EQ(FindDialect("Balt-System")->name(), "balt");
  EXPECT_EQ(FindDialect("fanuc"), nullptr);
  EXPECT_EQ(DialectList(), "ktapl, okuma, emco or balt");
  EXPECT_EQ(DialectChoices(), "ktapl|okuma|emco|balt");
  try {
    DialectOrThrow("fanuc");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("ktapl, okuma, emco or balt"), std::string::npos);
  }
}

TEST(Registry, MachineKindsAndFileKinds) {
  EXPECT_EQ(FindDialect("ktapl")->machine(), MachineKind::kMachiningCentre);
  EXPECT_EQ(FindDialect("okuma")->machine(), MachineKind::kLathe);
  EXPECT_EQ(FindDialect("emco")->machine(), MachineKind::kLathe);
  EXPECT_EQ(FindDialect("balt")->machine(), MachineKind::kMachiningCentre);
  // A kind only one dialect has belongs to it: fixture offset tables to KT-APL, schedules to Okuma.
  auto owners = [](FileKind k) {
    std::set<std::string> out;
    for (const Dialect* d : Dialects()) {
      for (FileKind x : d->kinds()) {
        if (x == k) out.emplace(d->name());
      }
    }
    return out;
  };
  EXPECT_EQ(owners(FileKind::kFixtureOffsets), std::set<std::string>{"ktapl"});
  EXPECT_EQ(owners(FileKind::kSchedule), std::set<std::string>{"okuma"});
  EXPECT_EQ(FindDialect("okuma")->KindFromName("SHAFT-1.SDF"), FileKind::kSchedule);
  EXPECT_EQ(FindDialect("ktapl")->KindFromName("PALLET38;FXT"), FileKind::kFixtureOffsets);
  EXPECT_EQ(FindDialect("ktapl")->KindFromName("PUMP341"), std::nullopt);
}

TEST(Registry, NameRules) {
  EXPECT_NO_THROW(FindDialect("ktapl")->CheckName("PUMP 341", FileKind::kPartProgram));
  EXPECT_THROW(FindDialect("ktapl")->CheckName("PALLET38", FileKind::kFixtureOffsets), Error);
  EXPECT_NO_THROW(FindDialect("okuma")->CheckName("SHAFT-1.SDF", FileKind::kSchedule));
  EXPECT_THROW(FindDialect("okuma")->CheckName("1SHAFT.MIN", FileKind::kPartProgram), Error);
  EXPECT_THROW(FindDialect("emco")->CheckName("../x", FileKind::kPartProgram), Error);
  EXPECT_THROW(FindDialect("balt")->CheckName(std::string(33, 'A'), FileKind::kPartProgram), Error);
}

TEST(Registry, EvidenceAndHeadings) {
  std::vector<Evidence> ev;
  FindDialect("ktapl")->FindEvidence("%\n(UTL,1001)\n", ev);
  ASSERT_FALSE(ev.empty());
  EXPECT_TRUE(ev[0].strong);
  ev.clear();
  FindDialect("okuma")->FindEvidence("O1234\nNAT01 G81\nVSET V1=2\n", ev);
  EXPECT_GE(ev.size(), 2u);
  ev.clear();
  FindDialect("balt")->FindEvidence("%:PART1\nE40=2\n", ev);
  EXPECT_EQ(ev.size(), 2u);
  ev.clear();
  FindDialect("emco")->FindEvidence("%\nN0000 G00 X10\nN0010 G84 X5 Z-20 D3=500\nN0020 M30\n", ev);
  EXPECT_FALSE(ev.empty());
  Heading h = FindDialect("ktapl")->ReadHeading("%\n(NAM,PUMP)\n(UTL,T12,7)\n(UCY,600)\n", {});
  EXPECT_EQ(h.name, "PUMP");
  EXPECT_EQ(h.tools, (std::vector<std::string>{"12", "7"}));
  EXPECT_EQ(h.cycle_s, 600);
  h = FindDialect("okuma")->ReadHeading("O1000\nG00 X10\nM02\nO1000\n", {});
  EXPECT_EQ(h.program_names, std::vector<std::string>{"O1000"});
  ASSERT_EQ(h.notices.size(), 1u);
  EXPECT_NE(h.notices[0].Format().find("line 4:"), std::string::npos);
}

TEST(Registry, RunsByNameUnimplementedDialectsRefuse) {
  RunOptions o;
  o.dialect = "ktapl";
  o.program_name = "T";
  o.program_text = "G71G0X1.F0\nM30\n";
  auto run = StartRun(o);
  EXPECT_EQ(run->Next().canon.op(), Op::kUnits);
  for (const Dialect* d : Dialects()) {
    if (d->implemented()) continue;
    o.dialect = std::string(d->name());
    try {
      StartRun(o);
      FAIL() << d->name();
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), Errc::kUnimplemented);
    }
  }
  o.dialect = "fanuc";
  EXPECT_THROW(StartRun(o), Error);
}

// The variables a station keeps between runs, by the dialect's rule (docs/station.md).
TEST(Registry, KeptVariables) {
  const Dialect& kt = DialectOrThrow("ktapl");
  EXPECT_EQ(kt.CheckVariable("L1500", 7), "");
  EXPECT_EQ(kt.CheckVariable("L2999", -99999999.0), "");
  for (const char* bad : {"L999", "L3000", "L01500", "l1500", "V1", "E12", "L15X0", ""}) {
    EXPECT_NE(kt.CheckVariable(bad, 1).find("L1000..L2999"), std::string::npos) << bad;
  }
  EXPECT_NE(kt.CheckVariable("L1500", 1e10).find("range"), std::string::npos);  // manual ln 8420
  for (const Dialect* d : Dialects()) {
    if (!d->implemented()) {
      EXPECT_NE(d->CheckVariable("V1", 1), "") << d->name();
    }
  }
  // What a KT-APL run reports is what the rule accepts.
  RunOptions o;
  o.dialect = "ktapl";
  o.program_name = "T";
  o.program_text = "(PAR,L1500=7.,L100=1.)\nM30\n";
  o.variables = {{"L1600", 2.5}};
  auto run = StartRun(o);
  while (run->Next().kind == Step::kCanon) {
  }
  for (const auto& [name, value] : run->Variables()) EXPECT_EQ(kt.CheckVariable(name, value), "") << name;
  EXPECT_EQ(run->Variables(), (std::map<std::string, double>{{"L1500", 7}, {"L1600", 2.5}}));
}

}  // namespace
}  // namespace cell::interp
