// The byte-level seam between the typed bus and a DDS implementation. A backend moves
// XCDR1 samples (4-byte encapsulation header included) of a named type; it never sees C++
// topic types, so adding a DDS vendor is one file of glue, not a second set of types.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace cell::bus {

// QoS presets (DESIGN.md §3); docs/architecture.md has the table.
enum class QosKind {
  kState,      // reliable, transient-local, keep-last 1 per key
  kCommand,    // reliable, volatile, keep-all
  kStream,     // reliable, volatile, keep-all; flow-controlled above the bus (credits)
  kTelemetry,  // best-effort, volatile, keep-last 1
  kEvent,      // reliable, transient-local, keep-last 256: late joiners get recent events
};

struct TypeSupport {
  std::string name;  // registered type name, "cell::StationStatus"
  bool keyed = false;
  size_t max_size = 0;  // bound of a serialized sample, header included
  size_t key_max_size = 0;
  // Big-endian key CDR (what serializeKey writes) from a serialized sample; false if undecodable.
  std::function<bool(const uint8_t* cdr, size_t n, std::vector<uint8_t>& key)> key_from_cdr;
};

struct RawSample {
  std::vector<uint8_t> cdr;  // encapsulation header + payload
  std::vector<uint8_t> key;  // big-endian key CDR; empty for unkeyed types
};

// Instances are never disposed through the bus: Fast DDS 2.9 mis-attributes disposes of
// string-keyed instances from other vendors, and liveness is a heartbeat on a state topic.
struct RawInfo {
  bool valid = true;  // false: an instance state change only, cdr empty (ignored above)
  // The writer's partition (BackendOptions::partition of the process that wrote it): "id/<identity>".
  // Under DDS Security the permissions grant each identity its own partition only, so this is the
  // authenticated identity of the writer. Empty when the backend could not tell.
  std::string writer_partition;
};

class RawWriter {
 public:
  virtual ~RawWriter() = default;
  virtual void Write(const RawSample& s) = 0;
  virtual int Matched() const = 0;
  // Readers matched since creation, a reader that was lost and came back counting again: a change
  // tells a volatile stream's producer that samples written meanwhile may never have arrived.
  virtual uint64_t TotalMatched() const = 0;
  // True once every matched reliable reader acknowledged everything written so far.
  virtual bool WaitForAcked(int timeout_ms) = 0;
};

class RawReader {
 public:
  virtual ~RawReader() = default;
  virtual int Matched() const = 0;
};

// Called on a backend thread; must return quickly.
using RawCallback = std::function<void(const RawSample&, const RawInfo&)>;

class Backend {
 public:
  virtual ~Backend() = default;
  virtual std::string Name() const = 0;
  virtual std::unique_ptr<RawWriter> CreateWriter(const std::string& topic, const TypeSupport& type,
                                                  QosKind qos) = 0;
  virtual std::unique_ptr<RawReader> CreateReader(const std::string& topic, const TypeSupport& type,
                                                  QosKind qos, RawCallback cb) = 0;
  // Other participants this one has discovered on its domain and not lost, or -1 when the backend cannot
  // tell. Zero shortly after joining means nothing else is on the domain: a client says "no cell" at once
  // instead of waiting out the discovery bound (issue 39 item 6).
  virtual int RemoteParticipants() const { return -1; }
  // When the stack's oldest receive call still running began (steady clock, ns since its epoch), or 0 when
  // none runs or the backend cannot tell. The same value for many seconds means a receive thread is stuck
  // (Participant::Watch): Fast DDS 2.9.1 deadlocks a receive thread against its timer thread.
  virtual int64_t OldestReceiveStartNs() const { return 0; }
};

// DDS Security (the builtin PKI-DH, Access-Permissions and AES-GCM-GMAC plugins): the identity's files as
// absolute paths (cell/security/pki.h finds them). Empty identity: an unsecured participant.
struct SecurityFiles {
  std::string identity;  // "scheduler", "interpreter-KT01": named in messages
  std::string ca;        // identity CA and permissions CA
  std::string governance, certificate, key, permissions;  // signed documents: *.p7s
  std::string crl;                                        // the CA's certificate revocation list; empty: none
};

struct BackendOptions {
  int domain = 101;
  std::string profile_path;  // where profile_xml came from (named in messages)
  std::string participant_name;
  std::string profile_xml;  // empty: the built-in loopback-only profile; else the profile's text with its
                            // ${VAR}s expanded (config::LoadDdsProfile)
  SecurityFiles security;
  // Every writer of the participant publishes in this one partition, "id/<identity>" (security::
  // WritePartition); every reader subscribes to "*" (every partition but the default one). Empty:
  // "id/unknown".
  std::string partition;
  // The participants one host's loopback discovery is sized for (config::DdsParticipants): the ports a
  // participant probes and the slots it may take. The LAN profiles set their own.
  int participants = 32;
  // The slot this participant asks for first (a host service's, HostServiceSlot), -1: the lowest free one
  // above the host services'.
  int preferred_slot = -1;
  // Announce this participant to the host services' slots only (of each peer host the profile names), not
  // to every slot of the cell, from a slot above the range the others announce themselves to. It then
  // discovers the host services and nothing else, and the stations never hear of it: on Fast DDS 2.9 a
  // newcomer costs every participant it meets (docs/operations.md §9.4, "What a newcomer costs"). A
  // multicast profile still announces it to every host.
  bool host_services_only = false;
  // A station's own process (the interpreter, the axis servo: IsStationProcess): it takes a slot from
  // kSharedSlots up and announces itself to the shared slots of each host (the host services and whole-cell
  // clients) and, on its own host, to its partner's slot (StationPartner, found by the mark of its
  // slots::Slot), never to another station's. Stations never talk to each other; meeting them was what made a
  // cell quadratic in its stations (docs/operations.md §9.5, "Who meets whom").
  bool station_process = false;
};

// Slots 0..kHostServiceSlots-1 of a host's loopback range are kept for the host services, so that a client
// knows where to find them without hearing the whole cell; every other participant takes a slot above them.
inline constexpr int kHostServiceSlots = 4;
// Slots 0..kSharedSlots-1 of a host are the host services' and the whole cell's clients' (cellctl, the
// dashboard); a station's processes take slots from kSharedSlots up when the range leaves room for them (the
// built-in profile's always does), so that another host's stations can announce themselves to this host's
// shared slots alone.
inline constexpr int kSharedSlots = 16;
// True for a station's own processes, named "cell-interpreter/<ID>" and "cell-axis-servo/<ID>".
bool IsStationProcess(const std::string& participant_name);
// The name of a station's other process (cell-interpreter/<ID> <-> cell-axis-servo/<ID>), empty for a name
// that is no station's process.
std::string StationPartner(const std::string& participant_name);
// The reserved slot of the host service a participant is named for ("cell-scheduler" 0, "cell-program-store"
// 1, "cell-inspection-writer" 2), -1 for any other name.
int HostServiceSlot(const std::string& participant_name);

// The identity a partition names ("" for a partition of another form). docs/security.md, "Partitions".
std::string IdentityOfPartition(const std::string& partition);

// A command-line tool's stdout and stderr are its own (JSON, one-line errors): before its first participant
// it drops the DDS stack's own log, whose errors it reports as cell::Error anyway. Services keep it, on
// stderr (the journal).
void SilenceDdsLog();
bool DdsLogSilenced();

// Both backends give the same semantics (QoS presets above, a 3 s participant lease, loopback-only by
// default: UDPv4 on 127.0.0.1, unicast discovery, no multicast, no shared memory).
std::unique_ptr<Backend> MakeFastDdsBackend(const BackendOptions& opts);  // Fast DDS 2.9
// Cyclone DDS 0.10 (approach A of reference/cyclone-rawcdr.md).
std::unique_ptr<Backend> MakeCycloneBackend(const BackendOptions& opts);

}  // namespace cell::bus
