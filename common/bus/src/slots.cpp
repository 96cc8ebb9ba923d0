#include "slots.h"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <string_view>
#include <utility>

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

std::vector<int> AnnouncedSlots(const BackendOptions& o, bool another_host, const Slot& slot) {
  int shared = 0;  // none: every slot
  if (o.host_services_only)
    shared = kHostServiceSlots;
  else if (o.station_process && (another_host || slot.marked()))
    shared = kSharedSlots;
  std::vector<int> out;
  for (int s = 0; s < shared; ++s) out.push_back(s);
  if (o.station_process && !another_host && slot.marked())
    for (int s : slot.found())
      if (s >= kSharedSlots && std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
  return out;
}

namespace {
constexpr std::string_view kMarkPrefix = "cell-name/";
constexpr std::string_view kReservationPrefix = "cell-slot/";

// A datagram socket bound to the abstract name `name` (sun_path[0] = 0), or -1 when another socket has it.
int BindAbstract(const std::string& name) {
  sockaddr_un a{};
  if (name.size() + 1 > sizeof a.sun_path) return -1;
  a.sun_family = AF_UNIX;
  std::memcpy(a.sun_path + 1, name.data(), name.size());
  const int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  const auto len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + 1 + name.size());
  if (bind(fd, reinterpret_cast<sockaddr*>(&a), len) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}
}  // namespace

std::vector<int> FindMarks(std::string_view text, int domain, const std::vector<std::string>& names,
                           int except) {
  // Each line ends in the socket's path; an abstract one is shown with '@' for its leading NUL.
  const std::string head = "@" + std::string(kMarkPrefix) + std::to_string(domain) + "/";
  std::vector<int> out;
  for (size_t at = text.find(head); at != std::string_view::npos; at = text.find(head, at + 1)) {
    const size_t end = std::min(text.find('\n', at), text.size());
    const std::string_view path = text.substr(at + head.size(), end - at - head.size());
    const size_t slash = path.rfind('/');
    if (slash == std::string_view::npos) continue;
    const std::string_view name = path.substr(0, slash), number = path.substr(slash + 1);
    if (number.empty() || number.size() > 3 ||
        number.find_first_not_of("0123456789") != std::string_view::npos)
      continue;
    const int slot = std::stoi(std::string(number));
    if (slot == except || std::find(names.begin(), names.end(), name) == names.end()) continue;
    if (std::find(out.begin(), out.end(), slot) == out.end()) out.push_back(slot);
  }
  return out;
}

Slot Slot::Take(const BackendOptions& o, int number) {
  Slot s;
  if (number < 0) return s;
  s.reservation_ =
      BindAbstract(std::string(kReservationPrefix) + std::to_string(o.domain) + "/" + std::to_string(number));
  if (s.reservation_ < 0) return s;
  s.number_ = number;
  const std::string partner = StationPartner(o.participant_name);
  if (!o.station_process || partner.empty()) return s;
  s.mark_ = BindAbstract(std::string(kMarkPrefix) + std::to_string(o.domain) + "/" + o.participant_name +
                         "/" + std::to_string(number));
  if (s.mark_ < 0) return s;
  std::ifstream f("/proc/net/unix");
  if (!f) {  // no list: the partner cannot be found, so announce to every slot
    close(s.mark_);
    s.mark_ = -1;
    return s;
  }
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  s.found_ = FindMarks(text, o.domain, {partner, o.participant_name}, number);
  return s;
}

void Slot::Close() {
  if (mark_ >= 0) close(mark_);
  if (reservation_ >= 0) close(reservation_);
  mark_ = reservation_ = number_ = -1;
  found_.clear();
}

Slot::~Slot() {
  Close();
}

Slot::Slot(Slot&& s) noexcept
    : number_(std::exchange(s.number_, -1)),
      reservation_(std::exchange(s.reservation_, -1)),
      mark_(std::exchange(s.mark_, -1)),
      found_(std::move(s.found_)) {}

Slot& Slot::operator=(Slot&& s) noexcept {
  if (this != &s) {
    Close();
    number_ = std::exchange(s.number_, -1);
    reservation_ = std::exchange(s.reservation_, -1);
    mark_ = std::exchange(s.mark_, -1);
    found_ = std::move(s.found_);
  }
  return *this;
}

namespace {

// The slots a participant of `o` tries, in order (Choose).
std::vector<int> Candidates(const BackendOptions& o, int range) {
  std::vector<int> out;
  if (o.host_services_only) {
    // From a random one of those above the range, so that clients started together (a script's commands in
    // parallel) seldom probe the same free slot.
    const int above = kSlotsPerDomain - range;
    if (above > 0) {
      std::random_device rd;
      const int start = static_cast<int>(rd() % static_cast<unsigned>(above));
      for (int i = 0; i < above; ++i) out.push_back(range + (start + i) % above);
    }
    // Else among the stations' slots, where no station announces itself (a partner's slot aside), rather
    // than among the shared ones, which every station of the cell announces itself to.
    for (int slot = FirstSlot(range, true); slot < range; ++slot) out.push_back(slot);
    for (int slot = FirstSlot(range); slot < FirstSlot(range, true); ++slot) out.push_back(slot);
    return out;
  }
  if (o.preferred_slot >= 0 && o.preferred_slot < range) out.push_back(o.preferred_slot);
  const int first = FirstSlot(range, o.station_process);
  for (int slot = first; slot < range; ++slot) out.push_back(slot);
  // Clients beyond the shared slots may have filled the stations' ones: a station's process then takes a
  // shared slot rather than none (it is met by other hosts' stations, as before the zones).
  for (int slot = FirstSlot(range); slot < first; ++slot) out.push_back(slot);
  return out;
}

}  // namespace

std::string NarrowCyclonePeers(const std::string& xml, const BackendOptions& o, const Slot& slot) {
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
    const auto announced = bare ? AnnouncedSlots(o, IsAnotherHost(address), slot) : std::vector<int>{};
    if (!announced.empty()) {
      for (int s : announced)
        out += "<Peer address=\"" + address + ":" + std::to_string(DiscoveryPort(o.domain, s)) + "\"/>";
    } else {
      out.append(xml, at, close + 2 - at);
    }
    from = close + 2;
  }
  out.append(xml, from, std::string::npos);
  return out;
}

Slot Choose(const BackendOptions& o, int range, const std::vector<int>& held, bool warn) {
  Slot chosen;
  for (int n : Candidates(o, range)) {
    const int port = DiscoveryPort(o.domain, n);
    if (std::find(held.begin(), held.end(), n) != held.end() || !PortFree(port) || !PortFree(port + 1))
      continue;
    chosen = Slot::Take(o, n);
    if (chosen.number() >= 0) break;
  }
  if (warn && o.preferred_slot >= 0 && chosen.number() != o.preferred_slot)
    spdlog::warn(
        "{}: the host service's slot {} (UDP port {}) is taken; clients that call the host services only "
        "will not find this one",
        o.participant_name, o.preferred_slot, DiscoveryPort(o.domain, o.preferred_slot));
  return chosen;
}

}  // namespace cell::bus::slots
