// The segment stream of the station core without DDS (docs/axis-servo.md "Credits", "Re-sends"): credits,
// re-sends after a lost match or a silent servo, and the ends of a run for want of a servo.
#include <gtest/gtest.h>

#include <chrono>
#include <optional>

#include "harness.h"

namespace cell::station::testing {
namespace {

// The seqs the machine ran for run `run`, in order.
std::vector<std::uint64_t> RanSeqs(const FakeServo& s, std::int32_t run) {
  std::vector<std::uint64_t> out;
  for (const auto& seg : s.ran)
    if (seg.run_id() == run) out.push_back(seg.seq());
  return out;
}

std::vector<std::uint64_t> OneTo(std::uint64_t n) {
  std::vector<std::uint64_t> v;
  for (std::uint64_t i = 1; i <= n; ++i) v.push_back(i);
  return v;
}

using SegmentStreamTest = StationHarness;

TEST_F(SegmentStreamTest, NeverMoreInFlightThanTheServoGranted) {
  Put("P", Moves(30));
  servo_.per_wait = 1;
  Dispatch(1, {"P"});
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  const std::uint64_t n = servo_.written.size();
  EXPECT_EQ(n, 32u);  // the rapid, 30 moves and END (the units op is not a segment)
  EXPECT_EQ(RanSeqs(servo_, 1), OneTo(n));
  // Capacity 4 (FakeServo's queue): at most 4 sent and not completed, at any time.
  EXPECT_LE(servo_.max_outstanding, 4u);
  EXPECT_GE(servo_.max_outstanding, 4u);
}

TEST_F(SegmentStreamTest, BeforeTheServoSpeaksOnlyTheInitialWindowLeaves) {
  Put("P", Moves(10));
  servo_.silent = true;
  std::size_t written_while_silent = 0;
  script_ = [&] {
    if (clock_.waits() == 5) {
      written_while_silent = servo_.written.size();
      servo_.silent = false;
    }
  };
  Dispatch(1, {"P"});
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_EQ(written_while_silent, SegmentStream::kInitialCredit);
}

TEST_F(SegmentStreamTest, SegmentsLostWhileUnmatchedAreSentAgainInOrderWhenTheServoMatchesAgain) {
  Put("P", Moves(12));
  servo_.per_wait = 1;
  bool lost = false;
  script_ = [&] {
    if (!lost && servo_.ran.size() == 3) {
      lost = true;
      servo_.drop_writes = 2;  // the next two writes never arrive (reader unmatched)
    } else if (lost && servo_.drop_writes == 0 && servo_.total_matched == 1) {
      servo_.total_matched = 2;  // matched again: TotalMatched() changed
    }
  };
  Dispatch(1, {"P"});
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  const std::uint64_t n = 14;               // the rapid, 12 moves, END
  EXPECT_EQ(RanSeqs(servo_, 1), OneTo(n));  // every seq once, in order
  EXPECT_GT(servo_.written.size(), n);      // some twice
}

TEST_F(SegmentStreamTest, ASilentServoWithSegmentsMissingGetsThemAgainAfterASecond) {
  Put("P", Moves(8));
  bool lost = false;
  script_ = [&] {
    if (!lost && servo_.ran.size() >= 2) {
      lost = true;
      servo_.drop_writes = 1;  // lost without a change of match (a deaf reader)
    }
  };
  Dispatch(1, {"P"});
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_EQ(RanSeqs(servo_, 1), OneTo(10));
  EXPECT_GT(servo_.written.size(), 10u);
}

TEST_F(SegmentStreamTest, AServoAlarmFailsTheRunWithTheAlarm) {
  Put("P", Moves(10));
  servo_.per_wait = 1;
  script_ = [&] {
    if (servo_.ran.size() == 4) {
      servo_.alarm_code = "500";
      servo_.alarm_text = "segment 5: X+ soft limit: 812.0000 > 800.0000";
    }
  };
  Dispatch(1, {"P"});
  auto end = RunOne(1);
  EXPECT_EQ(end.state(), cell::RUN_FAILED);
  EXPECT_EQ(end.reason(), "[500] segment 5: X+ soft limit: 812.0000 > 800.0000");
}

TEST_F(SegmentStreamTest, ARestartedServoFailsTheRun) {
  Put("P", Moves(10));
  servo_.per_wait = 1;
  script_ = [&] {
    if (servo_.ran.size() == 3) servo_.boot_id = 78;
  };
  Dispatch(1, {"P"});
  auto end = RunOne(1);
  EXPECT_EQ(end.state(), cell::RUN_FAILED);
  EXPECT_EQ(end.reason(), "axis servo of KT01 restarted during the run");
}

TEST_F(SegmentStreamTest, AServoThatVanishedFailsTheRunAfterTenSeconds) {
  Put("P", Moves(10));
  Clock::TimePoint gone{};
  servo_.per_wait = 1;
  script_ = [&] {
    if (servo_.ran.size() == 3 && servo_.matched == 1) {
      servo_.matched = 0;
      servo_.silent = true;
      gone = clock_.Now();
    }
  };
  Dispatch(1, {"P"});
  auto end = RunOne(1);
  EXPECT_EQ(end.state(), cell::RUN_FAILED);
  EXPECT_EQ(end.reason(), "axis servo of KT01 vanished during the run");
  EXPECT_GE(clock_.Now() - gone, SegmentStream::kServoGone);
  EXPECT_LE(clock_.Now() - gone, SegmentStream::kServoGone + std::chrono::seconds(1));
}

// A servo held for long says nothing; stopped past its lease then, it is unmatched for a moment and back.
// Vanished counts from the lost match, not from the last progress (which was 15 s before): the run goes on.
TEST_F(SegmentStreamTest, AMatchLostLateInALongHoldIsNotAVanishedServo) {
  Put("P", Moves(10));
  servo_.per_wait = 1;
  std::optional<Clock::TimePoint> held, lost;
  script_ = [&] {
    if (servo_.ran.size() == 3 && !held) {
      held = clock_.Now();
      servo_.hold = true;
    }
    if (held && !lost && clock_.Now() - *held > std::chrono::seconds(15)) {
      lost = clock_.Now();
      servo_.matched = 0;
    }
    if (lost && servo_.matched == 0 && clock_.Now() - *lost > std::chrono::seconds(3)) {
      servo_.matched = 1;
      ++servo_.total_matched;
      servo_.hold = false;
    }
  };
  Dispatch(1, {"P"});
  auto end = RunOne(1);
  EXPECT_EQ(end.state(), cell::RUN_COMPLETED) << end.reason();
  EXPECT_TRUE(lost.has_value());
  EXPECT_EQ(RanSeqs(servo_, 1), OneTo(servo_.ran.size()));
}

TEST_F(SegmentStreamTest, AServoThatTakesNothingFailsTheRun) {
  Put("P", Moves(10));
  servo_.per_wait = 1;
  script_ = [&] {
    if (servo_.ran.size() == 3) {
      servo_.silent = true;
      servo_.drop_writes = 1000;  // matched, deaf
    }
  };
  Dispatch(1, {"P"});
  auto end = RunOne(1);
  EXPECT_EQ(end.state(), cell::RUN_FAILED);
  EXPECT_EQ(end.reason(), "axis servo of KT01 has taken no segment for 10 s");
  EXPECT_EQ(servo_.rejoins, 1);  // once a run: still deaf after it, the run fails
}

// A one-way broken discovery (Fast DDS 2.9's one-sided lease expiry: a chaos run's BS01 failed every run so
// until restarted) heals by the interpreter joining the bus anew: the run re-sends what the servo missed,
// in order, and completes.
TEST_F(SegmentStreamTest, ADeafServoIsHealedByARejoinAndTheRunCompletes) {
  Put("P", Moves(10));
  servo_.per_wait = 1;
  Clock::TimePoint deaf_at{};
  script_ = [&] {
    if (servo_.ran.size() == 3 && !servo_.deaf_until_rejoin) {
      servo_.silent = true;
      servo_.drop_writes = 1000;  // matched, deaf
      servo_.deaf_until_rejoin = true;
      deaf_at = clock_.Now();
    }
  };
  Dispatch(1, {"P"});
  auto end = RunOne(1);
  EXPECT_EQ(end.state(), cell::RUN_COMPLETED) << end.reason();
  EXPECT_EQ(servo_.rejoins, 1);
  EXPECT_EQ(RanSeqs(servo_, 1), OneTo(servo_.ran.size()));  // each seq once, in order
  EXPECT_GE(clock_.Now() - deaf_at, SegmentStream::kServoGone);
}

// A run that waited longer than kServoGone (here a WAI on an input, KT-APL ln 4357) with everything taken
// goes on: the servo's silence while it owed nothing is not deafness. The END after the wait is drained at
// once, so the check runs before the servo's next report (the probe test failed so on a loaded machine).
TEST_F(SegmentStreamTest, ALongWaitWithNothingOwedIsNotSilence) {
  Put("WAI", "G71 G90\nG01 X0 Y0 Z100. F0\nX10. F1000.\n(WAI,I04D,1=1)\nM30\n");
  Dispatch(1, {"WAI"});
  const auto waited = SegmentStream::kServoGone + std::chrono::seconds(5);
  std::optional<Clock::TimePoint> wait_began;
  script_ = [&] {
    if (station_->Status().execution() != cell::EXECUTION_WAIT) return;
    if (!wait_began) wait_began = clock_.Now();
    if (clock_.Now() - *wait_began >= waited) SetInput("I04D.1", 1);
  };
  auto end = RunOne(1);
  EXPECT_EQ(end.state(), cell::RUN_COMPLETED) << end.reason();
  ASSERT_TRUE(wait_began.has_value());
  EXPECT_EQ(servo_.Ran(1, cell::SEGMENT_END).size(), 1u);
}

TEST_F(SegmentStreamTest, NoServoOnTheBusFailsTheRunBeforeItsFirstSegment) {
  Put("P", Moves(1));
  servo_.matched = 0;
  Dispatch(1, {"P"});
  auto end = RunOne(1);
  EXPECT_EQ(end.state(), cell::RUN_FAILED);
  EXPECT_EQ(end.reason(), "no axis servo for station KT01 on the bus");
  EXPECT_TRUE(servo_.written.empty());
  EXPECT_EQ(servo_.rejoins, 1);  // it joined the bus anew once before it failed
}

// A servo unmatched because discovery broke one way (a restarted servo its interpreter never matched, in a
// 32-station Fast DDS week) is matched after the interpreter joins the bus anew: the run goes on.
TEST_F(SegmentStreamTest, AServoUnmatchedAtTheStartIsFoundByARejoinAndTheRunCompletes) {
  Put("P", Moves(3));
  servo_.matched = 0;
  servo_.unmatched_until_rejoin = true;
  Dispatch(1, {"P"});
  auto end = RunOne(1);
  EXPECT_EQ(end.state(), cell::RUN_COMPLETED) << end.reason();
  EXPECT_EQ(servo_.rejoins, 1);
  EXPECT_EQ(RanSeqs(servo_, 1), OneTo(servo_.ran.size()));
}

// Where the run waits for the machine (M00's drain here), the servo is told: the last segment sent is written
// again, seq unchanged, flagged `waits`, so that a virtual-clock servo's look-ahead runs on at once instead
// of waiting for a refill that is not coming (docs/axis-servo.md "Clocks"). It runs once all the same.
TEST_F(SegmentStreamTest, AWaitForTheMachineFlagsTheLastSegmentSent) {
  Put("P", "G71 G90\nG01 X0 Y0 Z100. F1000.\nX10. M00\nX20.\nM30\n");
  Dispatch(1, {"P"});
  script_ = [&] {
    if (station_->Status().execution() == cell::EXECUTION_PROGRAM_STOPPED) Command(cell::STATION_CYCLE_START);
  };
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  int flagged = 0;
  std::uint64_t flagged_seq = 0, sent_before = 0, last = 0;
  for (std::size_t i = 0; i < servo_.written.size(); ++i) {
    const auto& w = servo_.written[i];
    last = std::max<std::uint64_t>(last, w.seq());
    if (!w.waits()) continue;
    ++flagged;
    flagged_seq = w.seq();
    sent_before = i > 0 ? servo_.written[i - 1].seq() : 0;
  }
  EXPECT_EQ(flagged, 1);  // the M00 (the END's drain: the servo runs on after END anyway)
  EXPECT_EQ(flagged_seq, sent_before);
  EXPECT_EQ(RanSeqs(servo_, 1), OneTo(last));
}

TEST_F(SegmentStreamTest, ProbeMovesWaitForTheServosResult) {
  // G22 (manual ln 11084): the contact position latches into L3042-L3049; the program reads it back.
  servo_.probe_contact_z = 53;
  Put("PRB", "G71 G90\nG01 X10. Y10. Z100. F0\nG22 Z0 F200.\n(PAR,L1500=L3044)\nM30\n");
  Dispatch(1, {"PRB"});
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  auto probes = servo_.Ran(1, cell::SEGMENT_PROBE);
  ASSERT_EQ(probes.size(), 1u);
  EXPECT_DOUBLE_EQ(probes[0].target()[2], 0.0);
  EXPECT_DOUBLE_EQ(probes[0].feed(), 200.0);  // the program's F (a probe move without F: the station's)
  EXPECT_FALSE(probes[0].probe_break());      // G22: trip on contact
  EXPECT_TRUE(probes[0].waits());             // nothing follows until its result is in
  EXPECT_DOUBLE_EQ(station_->MemoryState().image.variables.at("L1500"), 53.0);
}

}  // namespace
}  // namespace cell::station::testing
