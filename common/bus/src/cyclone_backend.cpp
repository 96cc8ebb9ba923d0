// Cyclone DDS 0.10 glue (reference/cyclone-rawcdr.md, approach A): topics come from the idlc
// descriptors of the same IDL, samples travel as the Fast CDR bytes of the generated C++
// types. Writes hand Cyclone a "carrier" serdata that it converts to the writer's own type,
// which checks the bytes against the idlc type and bounds; reads take Cyclone's checked copy.
#include <dlfcn.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <dds/ddsi/ddsi_sertype.h>

#include "cell/bus/backend.h"
#include "cell/error/error.h"
#include "cell_cyclone_registry.h"
#include "refused.h"
#include "slots.h"

namespace cell::bus {
namespace {

struct Carrier {
  ddsi_serdata c;
  uint32_t size;
  unsigned char* buf;  // follows the struct in the same allocation
};

uint32_t CarrierSize(const ddsi_serdata* d) {
  return reinterpret_cast<const Carrier*>(d)->size;
}
void CarrierToSer(const ddsi_serdata* d, size_t off, size_t sz, void* b) {
  std::memcpy(b, reinterpret_cast<const Carrier*>(d)->buf + off, sz);
}
ddsi_serdata* CarrierToSerRef(const ddsi_serdata* d, size_t off, size_t sz, ddsrt_iovec_t* r) {
  r->iov_base = reinterpret_cast<const Carrier*>(d)->buf + off;
  r->iov_len = static_cast<decltype(r->iov_len)>(sz);
  return ddsi_serdata_ref(d);
}
void CarrierToSerUnref(ddsi_serdata* d, const ddsrt_iovec_t*) {
  ddsi_serdata_unref(d);
}
void CarrierFree(ddsi_serdata* d) {
  std::free(d);
}
size_t CarrierPrint(const ddsi_sertype*, const ddsi_serdata*, char* buf, size_t size) {
  return static_cast<size_t>(std::snprintf(buf, size, "cell carrier"));
}
void CarrierTypeFree(ddsi_sertype*) {}

struct CarrierType {
  ddsi_serdata_ops sdops{};
  ddsi_sertype_ops stops{};
  ddsi_sertype st{};
  CarrierType() {
    sdops.get_size = CarrierSize;
    sdops.to_ser = CarrierToSer;
    sdops.to_ser_ref = CarrierToSerRef;
    sdops.to_ser_unref = CarrierToSerUnref;
    sdops.free = CarrierFree;
    sdops.print = CarrierPrint;
    stops.version = ddsi_sertype_v0;  // dds_writecdr converts only "v0" sertypes
    stops.free = CarrierTypeFree;
    ddsi_sertype_init(&st, "cell::carrier", &stops, &sdops, false);
  }
};

CarrierType& Carriers() {
  static CarrierType* t = new CarrierType();  // lives for the process: serdata may outlive callers
  return *t;
}

// DESIGN §3: loopback, unicast discovery with peer 127.0.0.1, no multicast, as many participant indices as
// the cell has participants (config::DdsParticipants: the ports Fast DDS probes with the same
// maxInitialPeersRange), no shared memory (Cyclone uses iceoryx only when configured). Its "auto" index is
// replaced by the slot the backend chose (slots.h) before Cyclone reads it, as a LAN profile's is.
std::string LoopbackXml(int participants) {
  return "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface address=\"127.0.0.1\"/>"
         "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
         "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>" +
         std::to_string(participants) +
         "</MaxAutoParticipantIndex><Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain>"
         "</CycloneDDS>";
}

constexpr const char* kAutoIndex = "<ParticipantIndex>auto</ParticipantIndex>";

// Appended to every configuration, the built-in one or a profile (Cyclone merges consecutive <CycloneDDS>
// documents, later ones winning): how much unacknowledged data a writer may hold before dds_write blocks.
// Cyclone's default (30 kB, growing towards 500 kB) made a writer block, then fail, as soon as one matched
// reader stopped acknowledging, e.g. a killed or stopped process whose 3 s lease had not run out yet: the
// program store's replies to every client failed while a killed client still counted as matched. Fast DDS
// queues instead (asynchronous publishing); 64 MB gives Cyclone the same behaviour for what a cell writes in
// a lease. Sockets ask for 16 MB receive buffers, as Fast DDS's do (the kernel caps the request at
// net.core.rmem_max): with the default a 32-station `cellctl up` dropped 50,000-290,000 datagrams. Writers
// heartbeat every 250 ms, not 100 ms, while a reader has not acknowledged: a 32-station `up` is CPU-bound
// on discovery (2 cores saturated), and at 100 ms heartbeats and the acknowledgements they ask for were about
// two thirds of its 2-4 million datagrams; at 250 ms an `up` received 1.0-1.6 million and took 10-17 s, not
// 14-47 s (docs/operations.md §9.4). Data still goes out at once; only the repair of a lost last sample
// waits.
constexpr const char* kCellXml =
    "<CycloneDDS><Domain Id=\"any\"><Internal><Watermarks><WhcHighInit>64 MB</WhcHighInit>"
    "<WhcHigh>64 MB</WhcHigh><WhcAdaptive>false</WhcAdaptive></Watermarks>"
    "<SocketReceiveBufferSize max=\"16MB\"/><HeartbeatInterval>250 ms</HeartbeatInterval>"
    "</Internal></Domain></CycloneDDS>";

// Cyclone has one domain (one configuration, one set of sockets) per id per process; the participants of a
// process share it (two Participants in one test, a rejoin making the backend again while another lives).
class Domains {
 public:
  // A configuration to try, and the slot it gives this process (none when the configuration fixes its own
  // index).
  struct Rendered {
    std::string xml;
    slots::Slot slot;
  };
  static dds_entity_t Acquire(int id, const std::string& config, const std::string& what) {
    return Acquire(
        id, config,
        [&](int attempt) {
          return attempt == 0 ? std::optional<Rendered>(Rendered{config, {}}) : std::nullopt;
        },
        what);
  }
  // `config(attempt)` gives the configuration to try (attempt 0, 1, ...), nullopt when there is no other: a
  // loopback slot chosen from free ports can be taken by another process before Cyclone binds it. A domain
  // this process already has is shared whatever its slot (one set of sockets per domain and process), when
  // it was made from the same `profile` (the configuration before its slot was chosen).
  static dds_entity_t Acquire(int id, const std::string& profile,
                              const std::function<std::optional<Rendered>(int)>& config,
                              const std::string& what) {
    std::lock_guard lk(Mu());
    auto& d = Map()[id];
    if (d.refs == 0) {
      dds_entity_t e = -1;
      std::optional<Rendered> tried;
      // An attempt that loses the race for its ports logs an error to stderr, then the next one succeeds:
      // the attempts are quiet, and when every one failed the last is made again aloud to log why.
      const uint32_t mask = dds_get_log_mask();
      dds_set_log_mask(0);
      for (int attempt = 0; e < 0; ++attempt) {
        auto c = config(attempt);
        if (!c) break;
        tried = std::move(c);
        e = dds_create_domain(static_cast<dds_domainid_t>(id), tried->xml.c_str());
      }
      dds_set_log_mask(mask);
      if (e < 0 && tried) e = dds_create_domain(static_cast<dds_domainid_t>(id), tried->xml.c_str());
      if (e < 0) {
        Map().erase(id);
        throw Error(Errc::kInvalidArgument, what + ": Cyclone DDS rejected the configuration (" +
                                                dds_strretcode(e) + "; its log names the element)");
      }
      d.entity = e;
      d.profile = profile;
      d.slot = std::move(tried->slot);
    } else if (d.profile != profile) {
      throw Error(Errc::kInvalidArgument, what + ": a process uses one Cyclone configuration per domain");
    }
    ++d.refs;
    return d.entity;
  }
  static void Release(int id) {
    std::lock_guard lk(Mu());
    auto it = Map().find(id);
    if (it == Map().end() || --it->second.refs > 0) return;
    dds_delete(it->second.entity);
    Map().erase(it);
  }

 private:
  struct Entry {
    dds_entity_t entity = 0;
    std::string profile;
    slots::Slot slot;  // held as long as the domain
    int refs = 0;
  };
  static std::mutex& Mu() {
    static std::mutex m;
    return m;
  }
  static std::map<int, Entry>& Map() {
    static auto* m = new std::map<int, Entry>();  // outlives static destruction order
    return *m;
  }
};

dds_qos_t* MakeQos(QosKind q) {
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, q == QosKind::kTelemetry ? DDS_RELIABILITY_BEST_EFFORT : DDS_RELIABILITY_RELIABLE,
                       DDS_SECS(1));
  dds_qset_durability(qos, (q == QosKind::kState || q == QosKind::kEvent) ? DDS_DURABILITY_TRANSIENT_LOCAL
                                                                          : DDS_DURABILITY_VOLATILE);
  int depth = 0;  // keep-all
  switch (q) {
    case QosKind::kState:
    case QosKind::kTelemetry:
      depth = 1;
      break;
    case QosKind::kEvent:
      depth = 256;
      break;
    default:
      break;
  }
  dds_qset_history(qos, depth ? DDS_HISTORY_KEEP_LAST : DDS_HISTORY_KEEP_ALL, depth);
  // What a transient-local writer keeps for late joiners is its durability-service history (default keep
  // last 1), not its history: without this an event topic would replay 1 sample, where Fast DDS replays 256.
  if (q == QosKind::kState || q == QosKind::kEvent)
    dds_qset_durability_service(qos, 0, DDS_HISTORY_KEEP_LAST, depth, DDS_LENGTH_UNLIMITED,
                                DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
  dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;  // Fast CDR 1.0 reads XCDR1 only
  dds_qset_data_representation(qos, 1, &xcdr1);
  return qos;
}

void Check(dds_return_t rc, const std::string& what) {
  if (rc < 0) throw Error(Errc::kInternal, what + ": " + dds_strretcode(rc));
}

class CycWriter : public RawWriter {
 public:
  explicit CycWriter(dds_entity_t w) : w_(w) {}
  ~CycWriter() override { dds_delete(w_); }
  void Write(const RawSample& s) override {
    size_t n = s.cdr.size(), padded = (n + 3) & ~size_t{3};
    auto* d = static_cast<Carrier*>(std::malloc(sizeof(Carrier) + padded));
    ddsi_serdata_init(&d->c, &Carriers().st, SDK_DATA);
    d->buf = reinterpret_cast<unsigned char*>(d + 1);
    std::memset(d->buf, 0, padded);
    std::memcpy(d->buf, s.cdr.data(), n);
    d->buf[3] = static_cast<unsigned char>(d->buf[3] | (padded - n));  // XTypes: padding count in options
    d->size = static_cast<uint32_t>(padded);
    d->c.timestamp.v = dds_time();
    dds_return_t rc = dds_writecdr(w_, &d->c);  // takes the reference
    if (rc == DDS_RETCODE_ERROR)                // the bytes do not fit the idlc type or its bounds
      throw Error(Errc::kInvalidArgument, std::string("Cyclone rejected the sample: ") + dds_strretcode(rc));
    if (rc < 0)  // e.g. a timeout: keep-all history full of samples a stalled reader has not acknowledged
      throw Error(Errc::kUnavailable, std::string("DDS write failed: ") + dds_strretcode(rc));
  }
  bool WaitForAcked(int timeout_ms) override {
    return dds_wait_for_acks(w_, DDS_MSECS(timeout_ms)) == DDS_RETCODE_OK;
  }
  int Matched() const override {
    dds_publication_matched_status_t st;
    dds_get_publication_matched_status(w_, &st);
    return static_cast<int>(st.current_count);
  }
  uint64_t TotalMatched() const override {
    dds_publication_matched_status_t st;
    dds_get_publication_matched_status(w_, &st);
    return st.total_count;
  }

 private:
  dds_entity_t w_;
};

class CycReader : public RawReader {
 public:
  explicit CycReader(RawCallback cb) : cb_(std::move(cb)) {}
  ~CycReader() override {
    dds_set_listener(r_, nullptr);
    std::lock_guard lk(mu_);
    dds_delete(r_);
  }
  void Attach(dds_entity_t r) { r_ = r; }
  int Matched() const override {
    dds_subscription_matched_status_t st;
    dds_get_subscription_matched_status(r_, &st);
    return static_cast<int>(st.current_count);
  }
  static void OnData(dds_entity_t reader, void* arg) { static_cast<CycReader*>(arg)->Drain(reader); }

 private:
  void Drain(dds_entity_t reader) {
    std::lock_guard lk(mu_);
    ddsi_serdata* sd[16];
    dds_sample_info_t si[16];
    int n;
    while ((n = dds_takecdr(reader, sd, 16, si, DDS_ANY_STATE)) > 0) {
      for (int i = 0; i < n; ++i) {
        if (si[i].valid_data) {
          RawSample s;
          ddsrt_iovec_t ref;
          uint32_t sz = ddsi_serdata_size(sd[i]);
          ddsi_serdata* r = ddsi_serdata_to_ser_ref(sd[i], 0, sz, &ref);
          auto* p = static_cast<const uint8_t*>(ref.iov_base);
          if (sz >= 4 && p[0] == 0 && p[1] <= 1) {  // XCDR1 only
            s.cdr.assign(p, p + sz);
            s.cdr[2] = s.cdr[3] = 0;  // options (padding count) mean nothing to Fast CDR
            cb_(s, RawInfo{true, WriterPartition(reader, si[i].publication_handle)});
          }
          ddsi_serdata_to_ser_unref(r, &ref);
        }
        ddsi_serdata_unref(sd[i]);
      }
    }
  }
  // The partition of the writer of a sample (RawInfo::writer_partition), from its matched publication's QoS,
  // remembered per writer.
  std::string WriterPartition(dds_entity_t reader, dds_instance_handle_t writer) {
    auto it = partitions_.find(writer);
    if (it != partitions_.end()) return it->second;
    std::string out;
    if (dds_builtintopic_endpoint_t* ep = dds_get_matched_publication_data(reader, writer)) {
      uint32_t n = 0;
      char** ps = nullptr;
      if (ep->qos && dds_qget_partition(ep->qos, &n, &ps)) {
        if (n == 1) out = ps[0];
        for (uint32_t i = 0; i < n; ++i) dds_free(ps[i]);
        dds_free(ps);
      }
      dds_builtintopic_free_endpoint(ep);
    } else {
      return std::string();  // not (or no longer) matched: ask again next time
    }
    if (partitions_.size() > 4096) partitions_.clear();  // writers come and go; bounded
    partitions_[writer] = out;
    return out;
  }
  RawCallback cb_;
  std::map<dds_instance_handle_t, std::string> partitions_;
  dds_entity_t r_ = 0;
  std::mutex mu_;
};

// Where Cyclone's DDS Security plugins are: beside libddsc, or (Debian) in its libddsc0debian/ directory.
std::string SecurityPlugin(const char* name) {
  Dl_info info{};
  std::filesystem::path dir = "/usr/lib/x86_64-linux-gnu";
  if (dladdr(reinterpret_cast<void*>(&dds_create_participant), &info) && info.dli_fname)
    dir = std::filesystem::path(info.dli_fname).parent_path();
  for (const auto& p : {dir / "libddsc0debian" / name, dir / name})
    if (std::filesystem::exists(p)) return p.string();
  return name;  // left to the loader's search path
}

// DDS Security 1.1 builtin plugins as participant properties (docs/security.md).
void Secure(const SecurityFiles& f, dds_qos_t* qos) {
  auto file = [](const std::string& path) { return "file:" + path; };
  dds_qset_prop(qos, "dds.sec.auth.library.path", SecurityPlugin("libdds_security_auth.so").c_str());
  dds_qset_prop(qos, "dds.sec.auth.library.init", "init_authentication");
  dds_qset_prop(qos, "dds.sec.auth.library.finalize", "finalize_authentication");
  dds_qset_prop(qos, "dds.sec.crypto.library.path", SecurityPlugin("libdds_security_crypto.so").c_str());
  dds_qset_prop(qos, "dds.sec.crypto.library.init", "init_crypto");
  dds_qset_prop(qos, "dds.sec.crypto.library.finalize", "finalize_crypto");
  dds_qset_prop(qos, "dds.sec.access.library.path", SecurityPlugin("libdds_security_ac.so").c_str());
  dds_qset_prop(qos, "dds.sec.access.library.init", "init_access_control");
  dds_qset_prop(qos, "dds.sec.access.library.finalize", "finalize_access_control");
  dds_qset_prop(qos, "dds.sec.auth.identity_ca", file(f.ca).c_str());
  dds_qset_prop(qos, "dds.sec.auth.identity_certificate", file(f.certificate).c_str());
  dds_qset_prop(qos, "dds.sec.auth.private_key", file(f.key).c_str());
  // Cyclone's own property for a CRL (0.10: org.eclipse.cyclonedds.sec.auth.crl).
  if (!f.crl.empty()) dds_qset_prop(qos, "org.eclipse.cyclonedds.sec.auth.crl", file(f.crl).c_str());
  dds_qset_prop(qos, "dds.sec.access.permissions_ca", file(f.ca).c_str());
  dds_qset_prop(qos, "dds.sec.access.governance", file(f.governance).c_str());
  dds_qset_prop(qos, "dds.sec.access.permissions", file(f.permissions).c_str());
}

class CycloneBackend : public Backend {
 public:
  explicit CycloneBackend(const BackendOptions& o)
      : domain_(o.domain), partition_(o.partition.empty() ? "id/unknown" : o.partition) {
    // Always an explicit configuration: neither CYCLONEDDS_URI nor a file elsewhere can widen the default.
    const std::string what =
        o.profile_xml.empty() ? "the built-in loopback profile" : "DDS profile " + o.profile_path;
    const std::string base = o.profile_xml.empty() ? LoopbackXml(o.participants) : o.profile_xml;
    if (base.find(kAutoIndex) == std::string::npos) {
      Domains::Acquire(domain_, base + kCellXml, what);  // a profile that fixes its own index
    } else {
      // The built-in profile and the shipped LAN profiles: the slot chosen as Fast DDS's backend does (not
      // Cyclone's auto, which would take the host services' slots), retried while other processes take it.
      Domains::Acquire(
          domain_, base + kCellXml,
          [&](int attempt) -> std::optional<Domains::Rendered> {
            if (attempt > 8) return std::nullopt;
            slots::Slot slot = slots::Choose(o, o.participants, {}, attempt == 0);
            if (slot.number() < 0) return std::nullopt;
            std::string xml = base;
            xml.replace(xml.find(kAutoIndex), std::strlen(kAutoIndex),
                        "<ParticipantIndex>" + std::to_string(slot.number()) + "</ParticipantIndex>");
            xml = slots::NarrowCyclonePeers(xml, o, slot) + kCellXml;
            return Domains::Rendered{std::move(xml), std::move(slot)};
          },
          what);
    }
    // A vanished process is noticed in ~3 s, as with Fast DDS (the participant lease; Cyclone's default is 10
    // s and it announces itself at 4/5 of the lease).
    dds_qos_t* qos = dds_create_qos();
    dds_qset_liveliness(qos, DDS_LIVELINESS_AUTOMATIC, DDS_SECS(3));
    if (!o.participant_name.empty()) dds_qset_entity_name(qos, o.participant_name.c_str());
    identity_ = o.security.identity;
    if (!identity_.empty()) Secure(o.security, qos);
    pp_ = dds_create_participant(static_cast<dds_domainid_t>(domain_), qos, nullptr);
    dds_delete_qos(qos);
    if (pp_ < 0) {
      Domains::Release(domain_);
      throw Error(Errc::kUnavailable,
                  "cannot create a Cyclone DDS participant on domain " + std::to_string(domain_) +
                      (identity_.empty() ? "" : " as security identity '" + identity_ + "'") + ": " +
                      dds_strretcode(pp_));
    }
    // docs/security.md, "Partitions": write in the identity's own partition, read every partition.
    dds_qos_t* pq = dds_create_qos();
    const char* own = partition_.c_str();
    dds_qset_partition(pq, 1, &own);
    pub_ = dds_create_publisher(pp_, pq, nullptr);
    const char* all = "*";
    dds_qset_partition(pq, 1, &all);
    sub_ = dds_create_subscriber(pp_, pq, nullptr);
    dds_delete_qos(pq);
    if (pub_ < 0 || sub_ < 0) {
      dds_delete(pp_);
      Domains::Release(domain_);
      throw Error(Errc::kInternal, "cannot create a Cyclone publisher or subscriber");
    }
  }
  ~CycloneBackend() override {
    dds_delete(pp_);
    Domains::Release(domain_);
  }
  std::string Name() const override { return "cyclonedds"; }

  // The DCPSParticipant builtin topic holds one instance per participant alive on the domain, this one's
  // included; the reader is made on first use (cellctl asks, services never do).
  int RemoteParticipants() const override {
    std::lock_guard lk(mu_);
    if (participants_ == 0) {
      participants_ = dds_create_reader(pp_, DDS_BUILTIN_TOPIC_DCPSPARTICIPANT, nullptr, nullptr);
      if (participants_ < 0) {
        participants_ = 0;
        return -1;
      }
    }
    dds_guid_t own{};
    if (dds_get_guid(pp_, &own) != DDS_RETCODE_OK) return -1;
    constexpr int kMax = 256;
    void* samples[kMax] = {};
    dds_sample_info_t infos[kMax];
    const int n = dds_read_mask(participants_, samples, infos, kMax, kMax,
                                DDS_ANY_SAMPLE_STATE | DDS_ANY_VIEW_STATE | DDS_ALIVE_INSTANCE_STATE);
    if (n < 0) return -1;
    int others = 0;
    for (int i = 0; i < n; ++i) {
      const auto* p = static_cast<const dds_builtintopic_participant_t*>(samples[i]);
      if (infos[i].valid_data && std::memcmp(&p->key, &own, sizeof own) != 0) ++others;
    }
    dds_return_loan(participants_, samples, n);
    return others;
  }

  std::unique_ptr<RawWriter> CreateWriter(const std::string& topic, const TypeSupport& type,
                                          QosKind q) override {
    dds_entity_t t = TopicFor(topic, type);
    dds_qos_t* qos = MakeQos(q);
    dds_entity_t w = dds_create_writer(pub_, t, qos, nullptr);
    dds_delete_qos(qos);
    if (w == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY) throw Refused(identity_, "publish", topic);
    Check(w, "Cyclone writer for " + topic);
    return std::make_unique<CycWriter>(w);
  }

  std::unique_ptr<RawReader> CreateReader(const std::string& topic, const TypeSupport& type, QosKind q,
                                          RawCallback cb) override {
    dds_entity_t t = TopicFor(topic, type);
    dds_qos_t* qos = MakeQos(q);
    auto reader = std::make_unique<CycReader>(std::move(cb));
    dds_listener_t* l = dds_create_listener(reader.get());
    dds_lset_data_available(l, &CycReader::OnData);
    dds_entity_t r = dds_create_reader(sub_, t, qos, l);
    dds_delete_listener(l);
    dds_delete_qos(qos);
    if (r == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY) throw Refused(identity_, "subscribe to", topic);
    Check(r, "Cyclone reader for " + topic);
    reader->Attach(r);
    return reader;
  }

 private:
  dds_entity_t TopicFor(const std::string& name, const TypeSupport& type) {
    std::lock_guard lk(mu_);
    const dds_topic_descriptor_t* desc = cell_cyclone_descriptor(type.name.c_str());
    if (!desc) throw Error(Errc::kInvalidArgument, "no idlc descriptor for " + type.name);
    dds_entity_t t = dds_create_topic(pp_, desc, name.c_str(), nullptr, nullptr);
    if (t == DDS_RETCODE_NOT_ALLOWED_BY_SECURITY) throw Refused(identity_, "use topic", name);
    Check(t, "Cyclone topic " + name);
    return t;
  }
  mutable std::mutex mu_;
  mutable dds_entity_t participants_ = 0;  // the DCPSParticipant reader, made on first use
  int domain_;
  std::string partition_;
  dds_entity_t pp_ = 0;
  dds_entity_t pub_ = 0;
  dds_entity_t sub_ = 0;
  std::string identity_;  // DDS Security identity; empty: unsecured
};

}  // namespace

std::unique_ptr<Backend> MakeCycloneBackend(const BackendOptions& opts) {
  return std::make_unique<CycloneBackend>(opts);
}

}  // namespace cell::bus
