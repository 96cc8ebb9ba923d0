#include "cell/scheduler/route.h"

#include <gtest/gtest.h>

#include "cell/error/error.h"

namespace cell::scheduler {
namespace {

TEST(OpSpec, ParsesStationsAndPrograms) {
  EXPECT_EQ(ParseOpSpec("KT01,KT02:PROG1,PROG2"), (OpSpec{{"KT01", "KT02"}, {"PROG1", "PROG2"}}));
  EXPECT_EQ(ParseOpSpec(" KT03 : GEAR HOUSING , \"A,B:C\""), (OpSpec{{"KT03"}, {"GEAR HOUSING", "A,B:C"}}));
}

TEST(OpSpec, Errors) {
  EXPECT_THROW(ParseOpSpec("KT01"), Error);
  try {
    ParseOpSpec("KT01,:P");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "--op 'KT01,:P': column 6: empty station name");
  }
  EXPECT_THROW(ParseOpSpec("KT01:\"P"), Error);
  // Station and program names follow their rules (docs/operations.md "Names"), with the column of the name.
  try {
    ParseOpSpec("KT01:A,../P");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("column 8: program '../P': no '/'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ParseOpSpec("KT 01:P"), Error);
  EXPECT_THROW(ParseRouteFile("ROUTE ../x\nOP KT01:P\n"), Error);
  std::string many = "KT01:";
  for (int i = 0; i < 76; ++i) many += (i ? ",P" : "P") + std::to_string(i);
  EXPECT_THROW(ParseOpSpec(many), Error);  // KT-APL seed line 842: 1 to 75 programs
}

TEST(RouteFile, ParsesAndRoundTrips) {
  const char* text =
      "# two routes\n"
      "ROUTE BRACKET\n"
      "  OP KT01,KT02 : OP10,OP20\n"
      "  op KT03 : \"A,B\"\n"
      "\n"
      "route HOUSING 2\n"
      "OP KT04:H1\n";
  auto routes = ParseRouteFile(text, "r.route");
  ASSERT_EQ(routes.size(), 2u);
  EXPECT_EQ(routes[0].name, "BRACKET");
  EXPECT_EQ(routes[0].ops.size(), 2u);
  EXPECT_EQ(routes[0].ops[1].programs, std::vector<std::string>{"A,B"});
  EXPECT_EQ(routes[1].name, "HOUSING 2");
  EXPECT_EQ(ParseRouteFile(FormatRouteFile(routes)), routes);
}

TEST(RouteFile, ErrorsHaveLineAndColumn) {
  auto err = [](const char* text) {
    try {
      ParseRouteFile(text, "r.route");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(err("OP KT01:P"), "r.route:1:1: error: OP before any ROUTE");
  EXPECT_EQ(err("ROUTE R\n  OP KT01,:P"), "r.route:2:11: error: empty station name");
  EXPECT_EQ(err("ROUTE R\nFOO"), "r.route:2:1: error: expected ROUTE, OP or a # comment");
  EXPECT_EQ(err("ROUTE R\n"), "r.route: error: route 'R' has no OP");
  EXPECT_EQ(err("ROUTE R\nOP A:B\nROUTE R"), "r.route:3:7: error: route 'R' defined twice");
}

}  // namespace
}  // namespace cell::scheduler
