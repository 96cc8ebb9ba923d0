// Cross-vendor interop: a Fast DDS peer and a Cyclone DDS peer (idlc descriptors of the same
// IDL) exchange a sample of every topic type in both directions, plus a string-keyed
// transient-local late joiner each way. Two real processes on the test's private domain.
#include <gtest/gtest.h>

#include "cell/idl/meta.h"
#include "cell/testing/process.h"

using namespace cell::testing;

TEST(Interop, FastDdsAndCycloneExchangeEveryTopicType) {
  ScopedTempDir tmp("cell-interop-");
  const std::string& dir = tmp.path();
  std::string peer = std::string(CELL_INTEROP_PEER);
  Process fast({peer, "fastdds"}, {}, dir + "/fast.out", dir + "/fast.err");
  Process cyc({peer, "cyclonedds"}, {}, dir + "/cyc.out", dir + "/cyc.err");
  auto a = fast.Wait(std::chrono::seconds(90));
  auto b = cyc.Wait(std::chrono::seconds(30));
  std::string fo = ReadFile(dir + "/fast.out"), co = ReadFile(dir + "/cyc.out");
  ASSERT_TRUE(a && b) << "peer hung\n" << fo << co;
  EXPECT_EQ(*a, 0) << fo << ReadFile(dir + "/fast.err");
  EXPECT_EQ(*b, 0) << co << ReadFile(dir + "/cyc.err");
  // Every topic type must be reported OK by both sides (the list is generated from the IDL).
#define CELL_EXPECT_OK(T)                                                                                  \
  EXPECT_NE(fo.find(std::string("OK fastdds ") + cell::idl::TypeMeta<T>::kName + "\n"), std::string::npos) \
      << "Cyclone -> Fast DDS failed for " << #T;                                                          \
  EXPECT_NE(co.find(std::string("OK cyclonedds ") + cell::idl::TypeMeta<T>::kName + "\n"),                 \
            std::string::npos)                                                                             \
      << "Fast DDS -> Cyclone failed for " << #T;
  CELL_IDL_FOR_EACH_TOPIC_TYPE(CELL_EXPECT_OK)
#undef CELL_EXPECT_OK
  EXPECT_NE(fo.find("OK fastdds late-joiner keyed by string (3 keys)"), std::string::npos) << fo;
  EXPECT_NE(co.find("OK cyclonedds late-joiner keyed by string (3 keys)"), std::string::npos) << co;
}
