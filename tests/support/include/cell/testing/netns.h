// Network namespaces joined by a veth pair, for tests that must see where DDS packets go (loopback_test: one
// namespace, nothing may leave loopback; two_host_test: two namespaces as two hosts of a cell). Needs root;
// names carry the pid, so tests of other worktrees running at the same time never collide. Everything is
// removed again by the destructor.
#pragma once

#include <string>
#include <vector>

namespace cell::testing {

class VethNamespaces {
 public:
  // `count` 1: namespace 0 holds veth end 0, end 1 stays in the caller's namespace (up, no address).
  // `count` 2: end i in namespace i. End i has the address Address(i) (a /30 of 10.<tag>.x.0) and, with
  // `multicast`, the multicast flag and a 224.0.0.0/4 route. IPv6 is off on the ends (no router chatter).
  VethNamespaces(const std::string& tag, int count, bool multicast);
  ~VethNamespaces();
  VethNamespaces(const VethNamespaces&) = delete;
  VethNamespaces& operator=(const VethNamespaces&) = delete;

  bool ok() const { return why_.empty(); }
  const std::string& why() const { return why_; }  // the step that failed, for GTEST_SKIP
  const std::string& name(int i) const { return names_.at(i); }
  const std::string& veth(int i) const { return veths_.at(i); }
  std::string Address(int i) const;  // IPv4 of end i, e.g. "10.252.17.1"
  // argv run inside namespace i (`ip netns exec NAME argv...`).
  std::vector<std::string> In(int i, std::vector<std::string> argv) const;
  // A counter of end i from /sys/class/net/<veth>/statistics/ (tx_packets, rx_bytes, ...); -1 on error.
  long Counter(int i, const std::string& stat) const;

 private:
  bool Step(const std::string& what, const std::string& cmd);
  std::vector<std::string> names_;  // 1 or 2 namespaces
  std::vector<std::string> veths_;  // both ends
  int count_ = 0;
  int subnet_ = 0;
  std::string why_;
};

}  // namespace cell::testing
