// What a program changed, applied to the memory as it stands (cell::station::ApplyToolChanges).
#include <gtest/gtest.h>

#include "cell/station/memory.h"

namespace cell::station {
namespace {

tooltable::ToolEntry E(const std::string& tool, double length) {
  tooltable::ToolEntry e;
  e.tool = tool;
  e.length = length;
  return e;
}

std::vector<std::string> Tools(const tooltable::ToolTable& t) {
  std::vector<std::string> out;
  for (const auto& e : t.entries()) out.push_back(e.tool + "=" + std::to_string(static_cast<int>(e.length)));
  return out;
}

TEST(ApplyToolChanges, KeepsWhatTheProgramDidNotTouch) {
  const tooltable::ToolTable before({E("1", 10), E("2", 20), E("3", 30)});
  const tooltable::ToolTable after({E("1", 11), E("3", 30), E("4", 40)});  // 1 changed, 2 gone, 4 new
  // Meanwhile the operator loaded 5 and changed 3.
  const tooltable::ToolTable now({E("1", 10), E("2", 20), E("3", 33), E("5", 50)});
  auto out = ApplyToolChanges(now, before, after);
  EXPECT_EQ(Tools(out), (std::vector<std::string>{"1=11", "3=33", "5=50", "4=40"}));
}

TEST(ApplyToolChanges, ProcessCompensationsByToolAndPallet) {
  const tooltable::ToolTable before({E("1", 10)}, {{"1", 38, 1, 0}, {"1", 39, 2, 0}});
  const tooltable::ToolTable after({E("1", 10)}, {{"1", 38, 5, 0}});
  auto out = ApplyToolChanges(before, before, after);
  ASSERT_EQ(out.process_comps().size(), 1u);
  EXPECT_EQ(out.process_comps()[0].pallet, 38);
  EXPECT_DOUBLE_EQ(out.process_comps()[0].length, 5);
}

}  // namespace
}  // namespace cell::station
