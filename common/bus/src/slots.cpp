#include "slots.h"

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <random>

#include <spdlog/spdlog.h>

#include "cell/bus/backend.h"

namespace cell::bus::slots {

int DiscoveryPort(int domain, int slot) {
  return 7400 + 250 * domain + 10 + 2 * slot;
}

bool PortFree(int port) {
  int fd = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) return false;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_ANY);  // conflicts with a bind on any address of this port
  bool free = bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  close(fd);
  return free;
}

int FirstSlot(int range) {
  return range >= 4 * kHostServiceSlots ? kHostServiceSlots : 0;
}

namespace {

bool Usable(int domain, int slot, const std::vector<int>& held) {
  const int port = DiscoveryPort(domain, slot);
  return std::find(held.begin(), held.end(), slot) == held.end() && PortFree(port) && PortFree(port + 1);
}

}  // namespace

int FreeSlot(int domain, int range, int preferred, const std::vector<int>& held) {
  if (preferred >= 0 && preferred < range && Usable(domain, preferred, held)) return preferred;
  for (int slot = FirstSlot(range); slot < range; ++slot)
    if (Usable(domain, slot, held)) return slot;
  return -1;
}

int ClientSlot(int domain, int range, const std::vector<int>& held) {
  // From a random one of them, so that clients started together (a script's commands in parallel) seldom
  // probe the same free slot and race to bind it.
  const int above = kSlotsPerDomain - range;
  if (above > 0) {
    std::random_device rd;
    const int start = static_cast<int>(rd() % static_cast<unsigned>(above));
    for (int i = 0; i < above; ++i) {
      const int slot = range + (start + i) % above;
      if (Usable(domain, slot, held)) return slot;
    }
  }
  return FreeSlot(domain, range, -1, held);
}

int Choose(const BackendOptions& o, int range, const std::vector<int>& held, bool warn) {
  const int slot = o.host_services_only ? ClientSlot(o.domain, range, held)
                                        : FreeSlot(o.domain, range, o.preferred_slot, held);
  if (warn && o.preferred_slot >= 0 && slot != o.preferred_slot)
    spdlog::warn(
        "{}: the host service's slot {} (UDP port {}) is taken; clients that call the host services only "
        "will not find this one",
        o.participant_name, o.preferred_slot, DiscoveryPort(o.domain, o.preferred_slot));
  return slot;
}

}  // namespace cell::bus::slots
