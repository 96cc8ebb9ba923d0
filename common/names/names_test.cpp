#include "cell/names/names.h"
#include "cell/names/program_ref.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

namespace cell::names {
namespace {

// Stands in for eprosima::fastrtps::fixed_string<N> (max_size, assign), which cuts on assignment.
template <std::size_t N>
struct Bounded {
  static constexpr std::size_t max_size = N;
  std::string value;
  void assign(const char* d, std::size_t n) { value.assign(d, std::min(n, N)); }
};

std::string Message(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kInvalidArgument);
    return e.what();
  }
  ADD_FAILURE() << "no error";
  return {};
}

TEST(Shown, EscapesAndShortens) {
  EXPECT_EQ(Shown("PUMP"), "'PUMP'");
  EXPECT_EQ(Shown("a\x1b[2Jb"), "'a\\x1b[2Jb'");
  EXPECT_EQ(Shown("a\\b'c"), "'a\\\\b\\'c'");
  EXPECT_EQ(Shown("\xc3\xa9"), "'\\xc3\\xa9'");
  std::string s = Shown(std::string(5000, 'A'));
  EXPECT_EQ(s, "'" + std::string(40, 'A') + "...' (5000 characters)");
}

TEST(Assign, RefusesWhatDoesNotFitInsteadOfCuttingIt) {
  Bounded<64> f;
  Assign(f, std::string(64, 'R'), "route name");
  EXPECT_EQ(f.value.size(), 64u);
  std::string m = Message([&] { Assign(f, std::string(65, 'R'), "route name"); });
  EXPECT_NE(m.find("route name 'RRRR"), std::string::npos) << m;
  EXPECT_NE(m.find("is 65 characters long; at most 64 are allowed"), std::string::npos) << m;
  EXPECT_EQ(f.value, std::string(64, 'R'));  // unchanged
  Message([&] { Assign(f, std::string("a\0b", 3), "name"); });
  std::vector<Bounded<8>> seq;
  Append(seq, "O1234", "program");
  EXPECT_THROW(Append(seq, "O123456789", "program"), Error);
  EXPECT_EQ(seq.size(), 1u);
}

TEST(Fit, CutsFreeTextVisiblyOnACharacterBoundary) {
  EXPECT_EQ(Fit("short", 10), "short");
  EXPECT_EQ(Fit("0123456789ABC", 10), "0123456...");
  EXPECT_EQ(Fit("012345\xc3\xa9xyz", 10), "012345...");  // é (2 bytes) at 6-7 is not split
  Bounded<10> f;
  AssignText(f, "0123456789ABC");
  EXPECT_EQ(f.value, "0123456...");
}

TEST(Rules, Stations) {
  EXPECT_NO_THROW(CheckStation("KT01"));
  EXPECT_NO_THROW(CheckStation("line_2-a"));
  EXPECT_NO_THROW(CheckNode("HOST"));
  for (std::string bad : std::vector<std::string>{"", "KT 01", "../x", "KT01\n", std::string(17, 'K')})
    EXPECT_THROW(CheckStation(bad), Error) << bad;
  EXPECT_THROW(CheckNode("HOST/KT01"), Error);
  // Balt-System memories (manual ln 1749: MP0-MP6, MP1 the default, which is the station's own namespace).
  EXPECT_NO_THROW(CheckNode("BS01/MP2"));
  EXPECT_NO_THROW(CheckNode("BS01/MP0"));
  EXPECT_THROW(CheckNode("BS01/MP1"), Error);
  EXPECT_THROW(CheckNode("BS01/MP7"), Error);
  EXPECT_THROW(CheckNode("BS01/HD"), Error);
  EXPECT_THROW(CheckNode("STATION-NAME-012/MP2"), Error);  // 20 characters: the node field holds 16
}

// "NODE:NAME" names a program in a namespace (a Balt-System station's memory); anything else is a plain name.
TEST(ProgramRefs, SplitAtANamespaceOnly) {
  auto r = SplitProgramRef("BS01/MP2:P9");
  EXPECT_EQ(r.node, "BS01/MP2");
  EXPECT_EQ(r.name, "P9");
  EXPECT_EQ(NodeStation(r.node), "BS01");
  r = SplitProgramRef("BS01:PROG1");
  EXPECT_EQ(r.node, "BS01");
  EXPECT_EQ(NodeStation(r.node), "BS01");
  r = SplitProgramRef("HOST:A.MIN");
  EXPECT_EQ(r.node, "HOST");
  EXPECT_EQ(NodeStation(r.node), "");
  for (const char* plain : {"P9", "A.B:C", "BS01/MP1:P9", "BS01/MP7:P9", "BS01:", ":P9", "O1000,O1,S.SUB"}) {
    r = SplitProgramRef(plain);
    EXPECT_EQ(r.node, "") << plain;
    EXPECT_EQ(r.name, plain);
  }
  CheckProgramRef("BS01/MP2:P9");
  EXPECT_THROW(CheckProgramRef("BS01/MP2:P/9"), Error);
  EXPECT_THROW(CheckProgramRef("BS01/MP3/P9"), Error);
}

TEST(Rules, Routes) {
  for (std::string ok :
       std::vector<std::string>{"PUMP", "BRACKET-A", "gear housing 2", "r.1_b", std::string(64, 'x')})
    EXPECT_NO_THROW(CheckRoute(ok)) << ok;
  EXPECT_NE(Message([] { CheckRoute("../x"); }).find("must begin with a letter or digit"), std::string::npos);
  EXPECT_NE(Message([] { CheckRoute("a/b"); }).find("only letters"), std::string::npos);
  EXPECT_NE(Message([] { CheckRoute("a\x1b]0;x\x07"); }).find("'a\\x1b]0;x\\x07'"), std::string::npos);
  EXPECT_NE(Message([] { CheckRoute(std::string(65, 'x')); }).find("65 characters long"), std::string::npos);
  EXPECT_NE(Message([] { CheckRoute(""); }).find("route name is empty"), std::string::npos);
  EXPECT_THROW(CheckRoute("PUMP "), Error);
  EXPECT_THROW(CheckRoute("P,Q"), Error);
}

TEST(Rules, ProgramsAndPatterns) {
  for (std::string ok : std::vector<std::string>{"O1234", "GEAR HOUSING, REV B", "PALLET38;FXT", "A.MIN",
                                                 std::string(128, 'p')})
    EXPECT_NO_THROW(CheckProgram(ok)) << ok;
  for (std::string bad : std::vector<std::string>{"", "a/b", "a\\b", "*", "a?", " A", "A ", "A\tB", ".", "..",
                                                  std::string(129, 'p')})
    EXPECT_THROW(CheckProgram(bad), Error) << bad;
  EXPECT_NO_THROW(CheckPattern("PUMP*"));
  EXPECT_THROW(CheckPattern("../*"), Error);
}

TEST(Rules, Records) {
  EXPECT_NO_THROW(CheckRecord("run-KT01-12.json"));
  EXPECT_NO_THROW(CheckRecord("KT01/*"));
  for (std::string bad : std::vector<std::string>{"", "../etc/passwd", "/etc/passwd", "KT01\\x", "a\x1b"})
    EXPECT_THROW(CheckRecord(bad), Error) << bad;
}

TEST(Rules, IdempotencyKeys) {
  EXPECT_EQ(WireKey("s7", "route-operate"), "s7:route-operate");
  EXPECT_EQ(WireKey(std::string(40, 'k'), "program-unprotect").size(), 58u);
  EXPECT_NE(Message([] { CheckKey(std::string(41, 'k')); }).find("41 characters long; at most 40"),
            std::string::npos);
  EXPECT_THROW(CheckKey(""), Error);
  EXPECT_THROW(CheckKey("a b"), Error);
  EXPECT_THROW(CheckKey("a\x01"), Error);
}

}  // namespace
}  // namespace cell::names
