// A host service matched yet silent for a whole call: the interpreter joins the bus anew and asks once more,
// at most once a minute (cell/station/silent_service.h).
#include "cell/station/silent_service.h"

#include <gtest/gtest.h>

#include <string>

#include "fakes.h"

namespace cell::station {
namespace {

using testing::FakeClock;

struct Harness {
  FakeClock clock;
  int rejoined = 0;
  SilentServiceRejoin healer{clock, [this] { ++rejoined; }};
};

TEST(SilentServiceRejoin, ATimeoutRejoinsAndTheSecondAskAnswers) {
  Harness h;
  int asked = 0;
  const std::string got = h.healer.Call("EM03", [&]() -> std::string {
    if (++asked == 1) throw Error(Errc::kTimeout, "cell/program_store did not answer within 30000 ms");
    EXPECT_EQ(h.rejoined, 1) << "asked again only after the rejoin";
    return "O1000";
  });
  EXPECT_EQ(got, "O1000");
  EXPECT_EQ(asked, 2);
  EXPECT_EQ(h.rejoined, 1);
}

TEST(SilentServiceRejoin, AnAnswerOrAnotherErrorRejoinsNothing) {
  Harness h;
  EXPECT_EQ(h.healer.Call("EM03", [] { return 7; }), 7);
  int asked = 0;
  // An unmatched service (kUnavailable) or a refusal is not discovery broken one way.
  for (Errc code : {Errc::kUnavailable, Errc::kNotFound, Errc::kInvalidArgument}) {
    EXPECT_THROW(h.healer.Call("EM03",
                               [&]() -> int {
                                 ++asked;
                                 throw Error(code, "no");
                               }),
                 Error);
  }
  EXPECT_EQ(asked, 3) << "asked once each";
  EXPECT_EQ(h.rejoined, 0);
}

TEST(SilentServiceRejoin, AtMostOnceAMinuteAndTheSecondTimeoutIsThrown) {
  Harness h;
  int asked = 0;
  auto silent = [&]() -> int {
    ++asked;
    throw Error(Errc::kTimeout, "cell/inspection did not answer within 5000 ms");
  };
  try {
    h.healer.Call("EM03", silent);
    FAIL() << "a second timeout after the rejoin is the call's outcome";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kTimeout);
  }
  EXPECT_EQ(asked, 2);
  EXPECT_EQ(h.rejoined, 1);
  // A caller that retries every 5 s: no second rejoin within the minute.
  h.clock.Advance(std::chrono::seconds(59));
  EXPECT_THROW(h.healer.Call("EM03", silent), Error);
  EXPECT_EQ(asked, 3);
  EXPECT_EQ(h.rejoined, 1);
  h.clock.Advance(std::chrono::seconds(1));
  EXPECT_THROW(h.healer.Call("EM03", silent), Error);
  EXPECT_EQ(asked, 5);
  EXPECT_EQ(h.rejoined, 2);
  EXPECT_EQ(h.healer.rejoins(), 2);
}

}  // namespace
}  // namespace cell::station
