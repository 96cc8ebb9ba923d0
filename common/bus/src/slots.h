// Participant slots on one host's loopback: which discovery ports a participant binds and which it announces
// itself to. Both stacks number ports the same way (RTPS 9.6.1.1: 7400 + 250·domain + 10 + 2·slot for the
// unicast discovery port, + 1 for user data), so a Fast DDS and a Cyclone process agree on every slot.
#pragma once

#include <string>
#include <string_view>
#include <vector>

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

// The slots a domain's ports leave room for (250 ports a domain, from 7410 + 250·domain two a slot; the
// cap of config::DdsParticipants).
inline constexpr int kSlotsPerDomain = 120;

// The lowest slot in [FirstSlot(range, station_process), range) whose two ports are free and that `held` does
// not name, then (a station's process) the lowest such shared one, or -1. A host service asks for its
// reserved slot first (`preferred`), then falls back to the others.
int FreeSlot(int domain, int range, int preferred, const std::vector<int>& held,
             bool station_process = false);

// A slot for a client of the host services only: above the range every participant announces itself to
// (a random free one), so that no station sends it an announcement and it is heard only by the services
// it announces itself to; the lowest free slot in the range when the range leaves none above it.
int ClientSlot(int domain, int range, const std::vector<int>& held);

// True when `address` is an IPv4 address (dotted quad) that is neither loopback nor one of this host's
// interfaces': a peer there is another host. A host name counts as this host (its peers are never narrowed:
// a station's partner is always found).
bool IsAnotherHost(const std::string& address);

// How many of a peer host's slots a participant of `o` announces itself to when the peer is named without a
// port: 0 for all of them (the range), else the first that many. A client of the host services only:
// kHostServiceSlots on every host. A station's process: kSharedSlots on another host, all of them on its own.
int AnnouncedSlots(const BackendOptions& o, bool another_host);

// A Cyclone configuration's <Peer address="A"/> elements without a port (every slot of that host) narrowed
// for `o` (AnnouncedSlots): one peer with its port for each slot announced to; the rest as written.
std::string NarrowCyclonePeers(const std::string& xml, const BackendOptions& o);

// The slot a participant of `o` takes on either stack: ClientSlot for a client of the host services only,
// else FreeSlot from its own (o.preferred_slot). A host service that does not get its own logs a warning
// when `warn` (clients of the host services only will not find it). -1 when every slot is taken.
int Choose(const BackendOptions& o, int range, const std::vector<int>& held, bool warn);

}  // namespace cell::bus::slots
