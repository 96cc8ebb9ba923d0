// Block stepping over the call stack, jump targets, the parse cache and the command queue.
#include "cell/interp/call_stack.h"

#include <gtest/gtest.h>

#include <string>

#include "cell/interp/canon_queue.h"
#include "cell/interp/parse_cache.h"

namespace cell::interp {
namespace {

struct Data {
  int repeats = 0;
};

TEST(CallStack, MainProgramLineByLineThenEnd) {
  CallStack<Data> s(ProgramText::FromString("N1 G0\r\nN2 X1\nN3"));
  std::vector<std::pair<std::string, int>> got;
  while (auto l = s.NextLine()) got.emplace_back(std::string(l->text), l->number);
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0], std::make_pair(std::string("N1 G0\r"), 1));  // '\r' is the dialect's to drop
  EXPECT_EQ(got[2], std::make_pair(std::string("N3"), 3));
  EXPECT_FALSE(s.NextLine());
}

TEST(CallStack, FramesPushPopAndReportTheirOwnLines) {
  auto lib = ProgramText::FromString("(DFS,S)\nA\nB\n(END)\n");
  CallStack<Data> s(ProgramText::FromString("X\nY\n"));
  EXPECT_EQ(s.NextLine()->text, "X");
  auto& f = s.Push({lib, 8, 12, 2}, "S");  // lines 2-3 of the library text
  f.data.repeats = 2;
  EXPECT_EQ(s.depth(), 2u);
  auto a = s.NextLine();
  EXPECT_EQ(a->text, "A");
  EXPECT_EQ(a->number, 2);
  EXPECT_EQ(s.NextLine()->text, "B");
  EXPECT_FALSE(s.NextLine());
  s.top().at = {s.top().span.begin, s.top().span.begin_line};  // a repeat: back to the body's start
  EXPECT_EQ(s.NextLine()->text, "A");
  s.Pop();
  EXPECT_EQ(s.NextLine()->text, "Y");
}

TEST(JumpTargets, MostRecentFirstBounded) {
  JumpTargets<int, 2> j;
  j.Remember(1, {10, 2});
  j.Remember(2, {20, 3});
  EXPECT_EQ(j.Find(1)->pos, 10u);  // now most recent
  j.Remember(3, {30, 4});          // pushes out 2, the least recently used
  EXPECT_FALSE(j.Find(2));
  EXPECT_EQ(j.Find(1)->line, 2);
  EXPECT_EQ(j.Find(3)->pos, 30u);
}

TEST(ParseCache, KeyedByTextAndOffsetAndPinsTheText) {
  ParseCache<std::string, 4> cache;
  auto t1 = ProgramText::FromString("abc");
  const ProgramText* raw = t1.get();
  cache.Put(t1, 1, "parsed b");
  EXPECT_EQ(*cache.Find(raw, 1), "parsed b");
  EXPECT_EQ(cache.Find(raw, 2), nullptr);
  t1.reset();  // the cache keeps the text alive: no reuse of its address
  EXPECT_EQ(*cache.Find(raw, 1), "parsed b");
}

TEST(CanonQueue, FifoAcrossGrowthAndSlotsStartAtTheirDefaults) {
  CanonQueue q;
  for (int i = 0; i < 40; ++i) q.Emplace<DwellOp>(i).seconds = i;
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(q.front().line, i);
    q.pop_front();
  }
  for (int i = 40; i < 70; ++i) q.Emplace<MessageOp>(i).text = "m";
  EXPECT_EQ(q.size(), 50u);
  EXPECT_EQ(q.front().As<DwellOp>().seconds, 20);
  while (q.front().op() == Op::kDwell) q.pop_front();
  EXPECT_EQ(q.front().line, 40);
  // A slot used for another op before starts from the new op's defaults.
  q.clear();
  q.Emplace<FileOpOp>(1).args = "x";
  q.pop_front();
  EXPECT_TRUE(q.Emplace<FileOpOp>(2).args.empty());
}

}  // namespace
}  // namespace cell::interp
