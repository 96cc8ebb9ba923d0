#include "slots.h"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <random>
#include <string>
#include <string_view>

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

int FirstSlot(int range, bool station_process) {
  if (station_process && range >= 2 * kSharedSlots) return kSharedSlots;
  return range >= 4 * kHostServiceSlots ? kHostServiceSlots : 0;
}

bool IsAnotherHost(const std::string& address) {
  in_addr a{};
  if (inet_pton(AF_INET, address.c_str(), &a) != 1) return false;
  if ((ntohl(a.s_addr) >> 24) == 127) return false;
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return false;
  bool local = false;
  for (ifaddrs* i = list; i && !local; i = i->ifa_next)
    if (i->ifa_addr && i->ifa_addr->sa_family == AF_INET)
      local = reinterpret_cast<const sockaddr_in*>(i->ifa_addr)->sin_addr.s_addr == a.s_addr;
  freeifaddrs(list);
  return !local;
}

int AnnouncedSlots(const BackendOptions& o, bool another_host) {
  if (o.host_services_only) return kHostServiceSlots;
  if (o.station_process && another_host) return kSharedSlots;
  return 0;
}

namespace {

bool Usable(int domain, int slot, const std::vector<int>& held) {
  const int port = DiscoveryPort(domain, slot);
  return std::find(held.begin(), held.end(), slot) == held.end() && PortFree(port) && PortFree(port + 1);
}

}  // namespace

int FreeSlot(int domain, int range, int preferred, const std::vector<int>& held, bool station_process) {
  if (preferred >= 0 && preferred < range && Usable(domain, preferred, held)) return preferred;
  const int first = FirstSlot(range, station_process);
  for (int slot = first; slot < range; ++slot)
    if (Usable(domain, slot, held)) return slot;
  // Clients beyond the shared slots may have filled the stations' ones: a station's process then takes a
  // shared slot rather than none (it is met by other hosts' stations, as before the zones).
  for (int slot = FirstSlot(range); slot < first; ++slot)
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

std::string NarrowCyclonePeers(const std::string& xml, const BackendOptions& o) {
  // <Peer address="A"/> with A holding no ':' (no port); anything else is kept as written. (Not std::regex:
  // GCC 12 with the sanitizers warns inside <regex>, and warnings are errors.)
  static constexpr std::string_view kOpen = "<Peer address=\"";
  std::string out;
  size_t from = 0;
  for (size_t at = xml.find(kOpen); at != std::string::npos; at = xml.find(kOpen, from)) {
    const size_t addr = at + kOpen.size();
    const size_t quote = xml.find('"', addr);
    const size_t close = quote == std::string::npos ? quote : xml.find("/>", quote);
    if (close == std::string::npos) break;
    const std::string address = xml.substr(addr, quote - addr);
    const bool bare =
        address.find(':') == std::string::npos && xml.find_first_not_of(" \t\r\n", quote + 1) == close;
    out.append(xml, from, at - from);
    const int announced = bare ? AnnouncedSlots(o, IsAnotherHost(address)) : 0;
    if (announced > 0) {
      for (int s = 0; s < announced; ++s)
        out += "<Peer address=\"" + address + ":" + std::to_string(DiscoveryPort(o.domain, s)) + "\"/>";
    } else {
      out.append(xml, at, close + 2 - at);
    }
    from = close + 2;
  }
  out.append(xml, from, std::string::npos);
  return out;
}

int Choose(const BackendOptions& o, int range, const std::vector<int>& held, bool warn) {
  const int slot = o.host_services_only
                       ? ClientSlot(o.domain, range, held)
                       : FreeSlot(o.domain, range, o.preferred_slot, held, o.station_process);
  if (warn && o.preferred_slot >= 0 && slot != o.preferred_slot)
    spdlog::warn(
        "{}: the host service's slot {} (UDP port {}) is taken; clients that call the host services only "
        "will not find this one",
        o.participant_name, o.preferred_slot, DiscoveryPort(o.domain, o.preferred_slot));
  return slot;
}

}  // namespace cell::bus::slots
