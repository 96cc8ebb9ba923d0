#include "cell/testing/netns.h"

#include <unistd.h>

#include <cstdlib>

#include "cell/testing/process.h"

namespace cell::testing {

namespace {
int Sh(const std::string& cmd) {
  return std::system((cmd + " >/dev/null 2>&1").c_str());
}
}  // namespace

VethNamespaces::VethNamespaces(const std::string& tag, int count, bool multicast) : count_(count) {
  const std::string pid = std::to_string(getpid());
  subnet_ = static_cast<int>(getpid() % 16000) * 4;  // a /30 of 10.<250+..>: unique per pid
  for (int i = 0; i < count; ++i)
    names_.push_back("cell" + tag + pid + (count > 1 ? "-" + std::to_string(i) : ""));
  // Interface names are at most 15 characters.
  const std::string v = "v" + tag.substr(0, 3) + std::to_string(getpid() % 1000000);
  veths_ = {v + "a", v + "b"};
  if (geteuid() != 0) {
    why_ = "needs root to create network namespaces";
    return;
  }
  for (auto& n : names_)
    if (!Step("ip netns add " + n, "ip netns add " + n) ||
        !Step("lo up in " + n, "ip -n " + n + " link set lo up"))
      return;
  if (!Step("a veth pair", "ip link add " + veths_[0] + " type veth peer name " + veths_[1])) return;
  for (int i = 0; i < 2; ++i) {
    if (i >= count) {  // the far end of a one-namespace setup stays here, up
      if (!Step("veth up", "ip link set " + veths_[i] + " up")) return;
      continue;
    }
    const std::string ns = names_[i], dev = veths_[i];
    if (!Step("veth into " + ns, "ip link set " + dev + " netns " + ns) ||
        !Step("no IPv6 on " + dev,
              "ip netns exec " + ns + " sysctl -w net.ipv6.conf." + dev + ".disable_ipv6=1") ||
        !Step("address " + Address(i), "ip -n " + ns + " addr add " + Address(i) + "/30 dev " + dev) ||
        !Step("veth up", "ip -n " + ns + " link set " + dev + " up" + (multicast ? " multicast on" : "")))
      return;
    if (multicast && !Step("multicast route", "ip -n " + ns + " route add 224.0.0.0/4 dev " + dev)) return;
  }
}

VethNamespaces::~VethNamespaces() {
  Sh("ip link del " +
     veths_[1]);  // either end removes the pair (the far end may be in the caller's namespace)
  for (auto& n : names_) {
    Sh("ip -n " + n + " link del " + veths_[0]);
    Sh("ip netns del " + n);
  }
}

bool VethNamespaces::Step(const std::string& what, const std::string& cmd) {
  if (Sh(cmd) == 0) return true;
  why_ = "cannot set up " + what + " (" + cmd + ")";
  return false;
}

std::string VethNamespaces::Address(int i) const {
  int host = subnet_ + 1 + i;  // .1 and .2 of the /30
  return "10." + std::to_string(250 + host / 65536) + "." + std::to_string(host / 256 % 256) + "." +
         std::to_string(host % 256);
}

std::vector<std::string> VethNamespaces::In(int i, std::vector<std::string> argv) const {
  std::vector<std::string> out = {"/usr/sbin/ip", "netns", "exec", names_.at(i)};
  out.insert(out.end(), argv.begin(), argv.end());
  return out;
}

long VethNamespaces::Counter(int i, const std::string& stat) const {
  RunResult r = RunCommand(In(i, {"/bin/cat", "/sys/class/net/" + veths_.at(i) + "/statistics/" + stat}));
  if (r.code != 0) return -1;
  try {
    return std::stol(r.out);
  } catch (...) {
    return -1;
  }
}

}  // namespace cell::testing
