// The station's discrete I/O: KT-APL SET and WAI (manual ln 3948-3973, 4343-4359), Okuma VDOUT, the station
// file's M-code map with the spindle interlocks of the Okuma lathe (OSP-E100L manual ln 1969-1978,
// 2008-2023), and what survives a restart.
#include <gtest/gtest.h>

#include "cell/station/io.h"
#include "harness.h"

namespace cell::station::testing {
namespace {

std::vector<IoBit> Bits(std::initializer_list<IoBit> b) {
  return b;
}

// ---- the specs ----

TEST(IoSpec, KtAplSetAndWaiAsTheManualWritesThem) {
  // ln 3969: N200(SET,O83D,0=1,O83E,3=0): word O83D bit 0 to 1, word O83E bit 3 to 0 (the dialect's spec is
  // the statement's body upper-cased without blanks).
  auto set = ParseOutputSpec("O83D,0=1,O83E,3=0");
  ASSERT_TRUE(set);
  EXPECT_FALSE(set->save);
  EXPECT_EQ(set->bits, Bits({{"O83D.0", 1}, {"O83E.3", 0}}));
  // ln 4357: N40(WAI,I04D,1=1, I03D,3=0): input word I04D bit 1 = 1 and I03D bit 3 = 0.
  EXPECT_EQ(ParseWaitSpec("I04D,1=1,I03D,3=0"), Bits({{"I04D.1", 1}, {"I03D.3", 0}}));
  EXPECT_EQ(Describe(*ParseWaitSpec("I04D,1=1,I03D,3=0")), "I04D.1=1 I03D.3=0");
  // A word may carry several bits; ln 3958-3960: 16-bit words, at most 8 bits a statement.
  EXPECT_EQ(ParseOutputSpec("O83D,0=1,15=1")->bits, Bits({{"O83D.0", 1}, {"O83D.15", 1}}));
  EXPECT_THROW(ParseOutputSpec("O83D,16=1"), Error);
  EXPECT_THROW(ParseOutputSpec("O83D,0=2"), Error);  // ln 3960: "either 1 (the on state) or 0"
  EXPECT_THROW(ParseOutputSpec("O83D,0=1,1=1,2=1,3=1,4=1,5=1,6=1,7=1,8=1"), Error);
  EXPECT_THROW(ParseWaitSpec("I04D"), Error);
  EXPECT_THROW(ParseWaitSpec("I04G,1=1"), Error);  // not a hexadecimal word address
  // ln 3962: (SET) without parameters saves the output states as the power-up state.
  EXPECT_TRUE(ParseOutputSpec("SAVE")->save);
  // Okuma's I/O variable as the dialect formats it (interp_vars.cpp): VDOUT[n]=v.
  EXPECT_EQ(ParseOutputSpec("VDOUT[12]=1")->bits, Bits({{"VDOUT[12]", 1}}));
  EXPECT_THROW(ParseOutputSpec("VDOUT[12]=5"), Error);
  // Other dialects' forms are not the station's to execute (Balt-System H outputs, EMCO M65).
  EXPECT_FALSE(ParseOutputSpec("H01"));
  EXPECT_FALSE(ParseWaitSpec("M65"));
}

TEST(IoSpec, BitNames) {
  EXPECT_TRUE(IsWordBitName("I04D.1", 'I'));
  EXPECT_TRUE(IsWordBitName("O83E.15", 'O'));
  EXPECT_FALSE(IsWordBitName("I04D.1", 'O'));
  EXPECT_FALSE(IsWordBitName("I3", 'I'));  // the old release's form
  EXPECT_FALSE(IsWordBitName("I04D.16", 'I'));
  EXPECT_FALSE(IsWordBitName("I04D.01", 'I'));
  EXPECT_FALSE(IsWordBitName("I12345.1", 'I'));
}

// ---- KT-APL on the station ----

using StationIoTest = StationHarness;

TEST_F(StationIoTest, SetChangesOutputsAfterTheMotionBeforeItAndSurvivesARestart) {
  Put("SET", "G71 G90\nG01 X0 Y0 Z100. F0\nX10. F1000.\n(SET,O83D,0=1,O83E,3=0)\nX20.\nM30\n");
  Dispatch(1, {"SET"});
  std::size_t ran_when_set = 0;
  script_ = [&] {
    if (ran_when_set == 0 && station_->Io().outputs.count("O83D.0")) ran_when_set = servo_.ran.size();
  };
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  // ln 3958-3959: "The outputs are set when the block goes active": both moves before it had run.
  EXPECT_GE(ran_when_set, 2u);
  auto io = station_->Io();
  EXPECT_EQ(io.outputs, (std::map<std::string, int>{{"O83D.0", 1}, {"O83E.3", 0}}));
  ASSERT_FALSE(io_.io.empty());
  ASSERT_EQ(io_.io.back().outputs().size(), 2u);
  EXPECT_EQ(io_.io.back().outputs()[0].name().to_string(), "O83D.0");
  EXPECT_EQ(io_.io.back().outputs()[0].value(), 1);

  SetInput("I04D.1", 1);
  Make();  // a restarted interpreter: outputs and inputs are where they were
  EXPECT_EQ(station_->Io().outputs, io.outputs);
  EXPECT_EQ(station_->Io().inputs, (std::map<std::string, int>{{"I04D.1", 1}}));
}

TEST_F(StationIoTest, SetWithoutArgumentsSavesThePowerUpState) {
  // ln 3962-3963: "(SET) ... set current output states as the power up state"; the deadload default is 0.
  Put("SAVE", "G71\n(SET,O83D,0=1,2=1)\n(SET)\n(SET,O83D,2=0)\nM30\n");
  Dispatch(1, {"SAVE"});
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  auto io = station_->Io();
  EXPECT_EQ(io.outputs, (std::map<std::string, int>{{"O83D.0", 1}, {"O83D.2", 0}}));
  EXPECT_EQ(io.power_up, (std::map<std::string, int>{{"O83D.0", 1}, {"O83D.2", 1}}));
  Make();
  EXPECT_EQ(station_->Io().power_up, io.power_up);
  ASSERT_FALSE(io_.io.empty());
  EXPECT_EQ(io_.io.back().outputs()[1].power_up(), 1);
}

TEST_F(StationIoTest, WaiBlocksTheRunInWaitUntilTheInputsMatch) {
  // ln 4357: N40(WAI,I04D,1=1, I03D,3=0). Two moves before it, one after.
  Put("WAI", "G71 G90\nG01 X0 Y0 Z100. F0\nX10. F1000.\n(WAI,I04D,1=1, I03D,3=0)\nX20.\nM30\n");
  SetInput("I03D.3", 1);  // not yet: bit 3 must be 0
  Dispatch(1, {"WAI"});
  int waits_in_wait = 0;
  std::uint64_t sent_while_waiting = 0;
  script_ = [&] {
    auto s = station_->Status();
    if (s.execution() != cell::EXECUTION_WAIT) return;
    EXPECT_EQ(s.status_text().to_string(), "waiting for I04D.1=1 I03D.3=0");
    if (++waits_in_wait == 1) sent_while_waiting = servo_.written.size();
    // Nothing after the WAI is streamed while it waits; the two moves before it have completed (the last
    // one was written again, flagged `waits`: the run waits for the machine).
    EXPECT_EQ(servo_.written.size(), sent_while_waiting);
    EXPECT_TRUE(servo_.written.back().waits());
    EXPECT_EQ(servo_.ran.size(), servo_.written.back().seq());
    if (waits_in_wait == 20) SetInput("I04D.1", 1);  // one of two: still waiting
    if (waits_in_wait == 40) SetInput("I03D.3", 0);  // both: it goes on
  };
  auto end = RunOne(1);
  EXPECT_EQ(end.state(), cell::RUN_COMPLETED) << end.reason();
  EXPECT_GE(waits_in_wait, 40);
  EXPECT_GE(sent_while_waiting, 2u);  // the rapid and the move before the WAI
  EXPECT_EQ(servo_.Ran(1, cell::SEGMENT_END).size(), 1u);
  EXPECT_EQ(station_->Status().status_text().to_string(), "");
  // The WAIT was published (viewers see it), and ACTIVE again after it.
  bool published_wait = false;
  for (const auto& s : io_.status)
    published_wait |=
        s.execution() == cell::EXECUTION_WAIT && s.status_text() == "waiting for I04D.1=1 I03D.3=0";
  EXPECT_TRUE(published_wait);
}

TEST_F(StationIoTest, WaiAlreadySatisfiedDoesNotWait) {
  Put("WAI", "G71\n(WAI,I04D,1=1)\nM30\n");
  SetInput("I04D.1", 1);
  Dispatch(1, {"WAI"});
  script_ = [&] { EXPECT_NE(station_->Status().execution(), cell::EXECUTION_WAIT); };
  EXPECT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
}

TEST_F(StationIoTest, FeedHoldShowsOverTheWaitAndCancelEndsIt) {
  Put("WAI", "G71\n(WAI,I04D,1=1)\nM30\n");
  Dispatch(1, {"WAI"});
  int n = 0;
  script_ = [&] {
    if (station_->Status().execution() == cell::EXECUTION_WAIT || servo_.hold) ++n;
    if (n == 5) servo_.hold = true;  // the operator's feed hold, as the servo reports it
    if (n == 10) {
      EXPECT_EQ(station_->Status().execution(), cell::EXECUTION_FEED_HOLD);
      servo_.hold = false;
    }
    if (n == 15) {
      EXPECT_EQ(station_->Status().execution(), cell::EXECUTION_WAIT);
      // [CLEAR ACTIVE] ends the suspension (ln 4354-4355): the cell's cancel of the run.
      EXPECT_EQ(Cancel(1).state(), cell::RUN_ACTIVE);
    }
  };
  auto end = RunOne(1);
  EXPECT_EQ(end.state(), cell::RUN_CANCELLED);
  EXPECT_EQ(station_->Status().execution(), cell::EXECUTION_STOPPED);
  EXPECT_EQ(station_->Status().status_text().to_string(), "");
}

TEST_F(StationIoTest, InputsAreKtAplBitsOfZeroOrOne) {
  EXPECT_EQ(SetInput("I04D.1", 1).revision(), 1u);
  EXPECT_THROW(SetInput("I3", 1), Error);  // the old release's bare bit number
  EXPECT_THROW(SetInput("O83D.0", 1), Error);
  EXPECT_THROW(SetInput("I04D.1", 2), Error);
  EXPECT_EQ(station_->Io().inputs, (std::map<std::string, int>{{"I04D.1", 1}}));
}

// ---- Okuma: VDOUT and the station file's M codes ----

class OkumaIoTest : public StationHarness {
 protected:
  void SetUp() override {
    StationHarness::SetUp();
    cfg_.dialect = "okuma";
    cfg_.tools.clear();
    // As deploy/stations/OK01.toml declares them.
    cfg_.aux = {{"chuck", "CHUCK", 83, 84, true, 184, 185, "OSP-E100L manual ln 2015-2023"},
                {"tailstock", "TAILSTOCK", 56, 55, true, 166, 167, "OSP-E100L manual ln 2008-2013"}};
    Make();
  }
  cell::RunStatus Run(std::int32_t id, const std::string& body) {
    Put("P" + std::to_string(id) + ".MIN", "%\nO100\n" + body + "M02\n%\n");
    Dispatch(id, {"P" + std::to_string(id) + ".MIN"});
    return RunOne(id);
  }
};

TEST_F(OkumaIoTest, ChuckAndTailstockFollowTheirMCodes) {
  // The station file's outputs are listed before any program set them.
  EXPECT_EQ(station_->Io().outputs, (std::map<std::string, int>{{"CHUCK", 0}, {"TAILSTOCK", 0}}));
  // ln 1977-1978: M83 chuck clamp; ln 1969-1970: M56 tailstock spindle advance.
  auto r = Run(1, "M83\nM56\n");
  EXPECT_EQ(r.state(), cell::RUN_COMPLETED) << r.reason();
  EXPECT_EQ(station_->Io().outputs, (std::map<std::string, int>{{"CHUCK", 1}, {"TAILSTOCK", 1}}));
  // M55 retract, M84 unclamp, with the spindle stopped.
  r = Run(2, "G00 X100 Z50 S500 M03\nM05\nM55\nM84\n");
  EXPECT_EQ(r.state(), cell::RUN_COMPLETED) << r.reason();
  EXPECT_EQ(station_->Io().outputs, (std::map<std::string, int>{{"CHUCK", 0}, {"TAILSTOCK", 0}}));
}

TEST_F(OkumaIoTest, InterlockedMCodesStopTheRunWhileTheSpindleRotates) {
  Run(1, "M83\n");
  // ln 2015-2016: "the chuck cannot normally be opened or closed while the spindle is rotating" (M184 ON,
  // the state after a reset, ln 2020).
  auto r = Run(2, "G00 X100 Z50 S500 M03\nM84\n");
  EXPECT_EQ(r.state(), cell::RUN_FAILED);
  EXPECT_NE(r.reason().to_string().find(
                "P2.MIN:4: error: M84 refused: the chuck interlock is ON (M185 turns it off)"),
            std::string::npos)
      << r.reason();
  EXPECT_EQ(station_->Status().condition(), cell::CONDITION_WARNING);
  EXPECT_EQ(station_->Io().outputs.at("CHUCK"), 1);  // still clamped
  // ln 2016: "chuck open/close operation is permitted even while the spindle is rotating by turning OFF the
  // interlock" (M185).
  r = Run(3, "G00 X100 Z50 S500 M03\nM185\nM84\n");
  EXPECT_EQ(r.state(), cell::RUN_COMPLETED) << r.reason();
  EXPECT_EQ(station_->Io().outputs.at("CHUCK"), 0);
  // ln 2008-2013: the tailstock likewise (M166 ON, the reset state; M167 OFF). Each program starts from the
  // reset state: M185 of the last program does not carry over to the chuck here.
  r = Run(4, "G00 X100 Z50 S500 M03\nM56\n");
  EXPECT_EQ(r.state(), cell::RUN_FAILED);
  EXPECT_NE(
      r.reason().to_string().find("M56 refused: the tailstock interlock is ON (M167 turns it off) and the "
                                  "spindle rotates; stop the spindle (M05) first (OSP-E100L manual ln "
                                  "2008-2013)"),
      std::string::npos)
      << r.reason();
  r = Run(5, "G00 X100 Z50 S500 M03\nM167\nM56\nM166\nM05\nM55\n");
  EXPECT_EQ(r.state(), cell::RUN_COMPLETED) << r.reason();
  EXPECT_EQ(station_->Io().outputs.at("TAILSTOCK"), 0);
}

TEST_F(OkumaIoTest, VdoutIsAnOutput) {
  auto r = Run(1, "VDOUT[12]=1\n");
  EXPECT_EQ(r.state(), cell::RUN_COMPLETED) << r.reason();
  EXPECT_EQ(station_->Io().outputs.at("VDOUT[12]"), 1);
  // The station's outputs are 0 or 1: another value stops the run at its block.
  r = Run(2, "VDOUT[12]=7\n");
  EXPECT_EQ(r.state(), cell::RUN_FAILED);
  EXPECT_NE(r.reason().to_string().find("P2.MIN:3: error: VDOUT[12]=7: a discrete bit is 0 or 1"),
            std::string::npos)
      << r.reason();
}

TEST(AuxIo, SpindleStateAndInterlocks) {
  const std::vector<config::AuxOutput> map = {{"chuck", "CHUCK", 83, 84, true, 184, 185, ""}};
  AuxIo aux(map);
  EXPECT_EQ(aux.Aux(83), (IoBit{"CHUCK", 1}));
  EXPECT_FALSE(aux.Aux(3));  // not in the map
  interp::SpindleOp on;
  on.dir = interp::SpindleDir::kCw;
  on.rpm = 500;
  aux.Spindle(on);
  EXPECT_TRUE(aux.SpindleRotates());
  EXPECT_THROW(aux.Aux(84), Error);
  EXPECT_FALSE(aux.Aux(185));
  EXPECT_EQ(aux.Aux(84), (IoBit{"CHUCK", 0}));
  EXPECT_FALSE(aux.Aux(184));
  EXPECT_THROW(aux.Aux(83), Error);
  interp::SpindleOp orient;
  orient.dir = interp::SpindleDir::kOrient;  // M19 ends rotation
  aux.Spindle(orient);
  EXPECT_EQ(aux.Aux(83), (IoBit{"CHUCK", 1}));
}

}  // namespace
}  // namespace cell::station::testing
