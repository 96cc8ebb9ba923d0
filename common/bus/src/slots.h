// Participant slots on one host's loopback: which discovery ports a participant binds and which it announces
// itself to. Both stacks number ports the same way (RTPS 9.6.1.1: 7400 + 250·domain + 10 + 2·slot for the
// unicast discovery port, + 1 for user data), so a Fast DDS and a Cyclone process agree on every slot.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "cell/config/dds.h"

namespace cell::bus {
struct BackendOptions;
}

namespace cell::bus::slots {

// The unicast discovery port of `slot` on `domain` (user data: this + 1).
int DiscoveryPort(int domain, int slot);

// True when no process on this host has bound `port` (UDP, any address).
bool PortFree(int port);

// The first slot a participant takes: the host services' (HostServiceSlot) are below it, reserved for them
// when the range is wide enough (the built-in loopback profile's always is: config::DdsParticipants >= 32);
// a station's process (BackendOptions::station_process) starts above the shared slots (kSharedSlots) when
// the range leaves as many again for stations.
int FirstSlot(int range, bool station_process = false);

// The slots a domain's ports leave room for (250 ports a domain, from 7410 + 250·domain two a slot): the
// cap of CELL_DDS_PARTICIPANTS; a computed range leaves the top config::kClientSlots of them free.
inline constexpr int kSlotsPerDomain = config::kMaxDdsParticipants;

// True when `address` is an IPv4 address (dotted quad) that is neither loopback nor one of this host's
// interfaces': a peer there is another host. A host name counts as this host (its peers are never narrowed:
// a station's partner is always found).
bool IsAnotherHost(const std::string& address);

// A slot this process holds, from choosing it until its participant has gone (docs/operations.md §9.5,
// "Who meets whom"). Two abstract Unix sockets (they belong to the network namespace, as the ports do, and
// vanish with the process: nothing goes stale, and neither the data directory nor systemd's PrivateTmp nor
// the user matters):
// - cell-slot/<domain>/<slot>, the reservation: bound by one process only, so two processes starting together
//   never both take a slot whose ports are still free (Fast DDS would move the later one to the next free
//   port, elsewhere than it marked);
// - cell-name/<domain>/<participant name>/<slot>, a station's process's mark. The processes of a host list
//   each other's in /proc/net/unix, so a station's process finds the slots of its partner (the station's
//   other process) and of any other live process of its own name (whom the identity claim must reach), and
//   announces itself to those and to the shared slots, never to the host's other stations.
class Slot {
 public:
  Slot() = default;  // none: the stack numbers it
  // Reserves `number` for a participant of `o` (none when another process has), then, for a station's
  // process (BackendOptions::station_process), marks it and finds its partner's and namesakes'. Each marks
  // before it looks, so of two started together at least one finds the other, and the other answers it.
  // Unmarked (it announces itself to every slot of its host) when it cannot mark or list.
  static Slot Take(const BackendOptions& o, int number);
  ~Slot();
  Slot(Slot&& s) noexcept;
  Slot& operator=(Slot&& s) noexcept;
  Slot(const Slot&) = delete;
  Slot& operator=(const Slot&) = delete;
  int number() const { return number_; }  // -1: none
  bool marked() const { return mark_ >= 0; }
  // The partner's slots and those of others of this process's name, as found when marked.
  const std::vector<int>& found() const { return found_; }

 private:
  void Close();
  int number_ = -1;
  int reservation_ = -1;
  int mark_ = -1;
  std::vector<int> found_;
};

// The slots marked (Slot) on `domain` by participants named `names` in the text of /proc/net/unix, but
// `except`.
std::vector<int> FindMarks(std::string_view proc_net_unix, int domain, const std::vector<std::string>& names,
                           int except);

// The slots of a peer host a participant of `o` announces itself to when the peer is named without a port:
// none (empty) for all of them (the range). A client of the host services only: the kHostServiceSlots on
// every host. A station's process: the kSharedSlots of another host; of its own host, once its slot is
// marked, the shared ones and those the mark found, else all.
std::vector<int> AnnouncedSlots(const BackendOptions& o, bool another_host, const Slot& slot = Slot{});

// A Cyclone configuration's <Peer address="A"/> elements without a port (every slot of that host) narrowed
// for `o` (AnnouncedSlots): one peer with its port for each slot announced to; the rest as written.
std::string NarrowCyclonePeers(const std::string& xml, const BackendOptions& o, const Slot& slot = Slot{});

// The slot a participant of `o` takes on either stack, held (Slot) until it is released: for a client of the
// host services only, a random free one above the range every participant announces itself to, so that no
// station sends it an announcement and it is heard only by the services it announces itself to (else the
// lowest free station slot, which no station announces itself to); else its own (o.preferred_slot), then the
// lowest free one from FirstSlot(range, o.station_process), then (a station's process) the lowest free shared
// one. Free: neither port bound, not reserved by another process, not in `held`. A host service that does not
// get its own logs a warning when `warn` (clients of the host services only will not find it). None
// (number() -1) when every slot is taken.
Slot Choose(const BackendOptions& o, int range, const std::vector<int>& held, bool warn);

}  // namespace cell::bus::slots
