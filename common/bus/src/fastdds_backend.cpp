// Fast DDS 2.9 glue: one generic TopicDataType that carries XCDR1 bytes under the real type
// name, so Fast DDS matches, keys and hashes exactly as its generated PubSubTypes would.
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <set>
#include <sstream>
#include <vector>

#include <fastdds/rtps/common/Locator.h>
#include <fastdds/rtps/transport/ChainingTransport.h>
#include <fastdds/rtps/transport/ChainingTransportDescriptor.h>
#include <fastdds/rtps/transport/UDPTransportDescriptor.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <fastrtps/utils/md5.h>
#include <spdlog/spdlog.h>
#include <fastdds/dds/core/policy/QosPolicies.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/log/StdoutErrConsumer.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include "cell/bus/backend.h"
#include "cell/error/error.h"
#include "fastdds_lease_check.h"
#include "refused.h"
#include "slots.h"

namespace cell::bus {
namespace {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;

namespace frtps = eprosima::fastdds::rtps;

// Fast DDS 2.9 sends a new participant's first announcement (BuiltinProtocols::enable) before it starts
// reception (RTPSParticipantImpl::enable registers its receivers only afterwards) and drops what arrives in
// between (ReceiverResource::OnDataReceived without a receiver). A running participant answers a new one
// once, at once (PDPListener: a new participant resets its announcement), so that answer was lost and the new
// process waited for the running one's next periodic announcement, up to 1 s (cellctl: 0.5-1 s a verb). The
// gate holds what arrives until the backend opens it, once create_participant has returned, and hands it on
// then, in order (docs/architecture.md, "Discovery latency").
class ReceiveGate {
 public:
  // True when held: Open() delivers it.
  bool Hold(frtps::TransportReceiverInterface* next, const rtps::octet* data, uint32_t size,
            const rtps::Locator_t& local, const rtps::Locator_t& remote) {
    std::lock_guard lk(mu_);
    if (open_) return false;
    held_.push_back({next, std::vector<rtps::octet>(data, data + size), local, remote});
    return true;
  }
  // A receive call in progress on this thread, from Enter to Leave: its start in the thread's slot (one slot
  // a receive thread; a participant has a handful). OldestNs is what Participant::Watch reads.
  int Enter() {
    thread_local const ReceiveGate* owner = nullptr;
    thread_local int slot = -1;
    if (owner != this) {
      owner = this;
      slot = next_slot_.fetch_add(1);
      if (slot >= kSlots) slot = -1;  // more threads than slots: this one is not watched
    }
    if (slot >= 0) busy_[slot].store(NowNs(), std::memory_order_relaxed);
    return slot;
  }
  void Leave(int slot) {
    if (slot >= 0) busy_[slot].store(0, std::memory_order_relaxed);
  }
  int64_t OldestNs() const {
    int64_t oldest = 0;
    for (auto& b : busy_) {
      const int64_t t = b.load(std::memory_order_relaxed);
      if (t != 0 && (oldest == 0 || t < oldest)) oldest = t;
    }
    return oldest;
  }

  // Only while the participant lives: the receivers held here are its own.
  void Open() {
    std::lock_guard lk(mu_);  // a datagram arriving meanwhile waits behind the held ones
    for (auto& h : held_)
      h.next->OnDataReceived(h.data.data(), static_cast<uint32_t>(h.data.size()), h.local, h.remote);
    held_.clear();
    open_ = true;
  }

 private:
  struct Held {
    frtps::TransportReceiverInterface* next;
    std::vector<rtps::octet> data;
    rtps::Locator_t local, remote;
  };
  static int64_t NowNs() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }
  static constexpr int kSlots = 32;
  std::mutex mu_;
  bool open_ = false;
  std::vector<Held> held_;
  std::array<std::atomic<int64_t>, kSlots> busy_{};
  std::atomic<int> next_slot_{0};
};

class GatedTransport : public frtps::ChainingTransport {
 public:
  GatedTransport(const frtps::ChainingTransportDescriptor& d, std::shared_ptr<ReceiveGate> gate)
      : ChainingTransport(d), gate_(std::move(gate)) {}
  frtps::TransportDescriptorInterface* get_configuration() override {
    return low_level_transport_->get_configuration();
  }
  bool send(rtps::SenderResource* low, const rtps::octet* buf, uint32_t size, rtps::LocatorsIterator* begin,
            rtps::LocatorsIterator* end, const std::chrono::steady_clock::time_point& timeout) override {
    return low->send(buf, size, begin, end, timeout);
  }
  void receive(frtps::TransportReceiverInterface* next, const rtps::octet* buf, uint32_t size,
               const rtps::Locator_t& local, const rtps::Locator_t& remote) override {
    if (gate_->Hold(next, buf, size, local, remote)) return;
    const int slot = gate_->Enter();
    next->OnDataReceived(buf, size, local, remote);
    gate_->Leave(slot);
  }

 private:
  std::shared_ptr<ReceiveGate> gate_;
};

struct GatedDescriptor : public frtps::ChainingTransportDescriptor {
  GatedDescriptor(std::shared_ptr<frtps::TransportDescriptorInterface> low, std::shared_ptr<ReceiveGate> g)
      : ChainingTransportDescriptor(std::move(low)), gate(std::move(g)) {}
  frtps::TransportInterface* create_transport() const override { return new GatedTransport(*this, gate); }
  std::shared_ptr<ReceiveGate> gate;
};

class CdrType : public dds::TopicDataType {
 public:
  explicit CdrType(const TypeSupport& ts) : ts_(ts) {
    setName(ts.name.c_str());
    m_typeSize = static_cast<uint32_t>(ts.max_size + 4);
    m_isGetKeyDefined = ts.keyed;
  }

  bool serialize(void* data, rtps::SerializedPayload_t* payload) override {
    auto* s = static_cast<RawSample*>(data);
    if (s->cdr.size() < 4) return false;
    if (payload->max_size < s->cdr.size()) payload->reserve(static_cast<uint32_t>(s->cdr.size()));
    std::memcpy(payload->data, s->cdr.data(), s->cdr.size());
    payload->length = static_cast<uint32_t>(s->cdr.size());
    payload->encapsulation = s->cdr[1] == 1 ? CDR_LE : CDR_BE;
    return true;
  }

  bool deserialize(rtps::SerializedPayload_t* payload, void* data) override {
    auto* s = static_cast<RawSample*>(data);
    s->cdr.assign(payload->data, payload->data + payload->length);
    s->key.clear();
    return true;
  }

  std::function<uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data] { return static_cast<uint32_t>(static_cast<RawSample*>(data)->cdr.size()); };
  }

  void* createData() override { return new RawSample(); }
  void deleteData(void* data) override { delete static_cast<RawSample*>(data); }

  // Same rule as fastddsgen's getKey: big-endian key CDR, MD5 when it can exceed 16 bytes.
  bool getKey(void* data, rtps::InstanceHandle_t* handle, bool force_md5) override {
    if (!ts_.keyed) return false;
    auto* s = static_cast<RawSample*>(data);
    std::vector<uint8_t> key = s->key;
    if (key.empty() && !ts_.key_from_cdr(s->cdr.data(), s->cdr.size(), key)) return false;
    if (force_md5 || ts_.key_max_size > 16) {
      ::MD5 md5;
      md5.init();
      md5.update(key.data(), static_cast<unsigned int>(key.size()));
      md5.finalize();
      for (int i = 0; i < 16; ++i) handle->value[i] = md5.digest[i];
    } else {
      for (size_t i = 0; i < 16; ++i) handle->value[i] = i < key.size() ? key[i] : 0;
    }
    return true;
  }

 private:
  TypeSupport ts_;
};

void ApplyQos(QosKind q, dds::ReliabilityQosPolicy& rel, dds::DurabilityQosPolicy& dur,
              dds::HistoryQosPolicy& hist) {
  rel.kind = q == QosKind::kTelemetry ? dds::BEST_EFFORT_RELIABILITY_QOS : dds::RELIABLE_RELIABILITY_QOS;
  dur.kind = (q == QosKind::kState || q == QosKind::kEvent) ? dds::TRANSIENT_LOCAL_DURABILITY_QOS
                                                            : dds::VOLATILE_DURABILITY_QOS;
  switch (q) {
    case QosKind::kState:
    case QosKind::kTelemetry:
      hist.kind = dds::KEEP_LAST_HISTORY_QOS;
      hist.depth = 1;
      break;
    case QosKind::kEvent:
      hist.kind = dds::KEEP_LAST_HISTORY_QOS;
      hist.depth = 256;
      break;
    case QosKind::kCommand:
    case QosKind::kStream:
      hist.kind = dds::KEEP_ALL_HISTORY_QOS;
      break;
  }
}

class FastWriter : public RawWriter {
 public:
  FastWriter(dds::Publisher* pub, dds::DataWriter* w, bool sweep) : pub_(pub), w_(w), sweep_(sweep) {}
  ~FastWriter() override { pub_->delete_datawriter(w_); }
  void Write(const RawSample& s) override {
    std::unique_lock lk(mu_, std::defer_lock);
    if (sweep_) {
      lk.lock();
      Sweep();
    }
    if (!w_->write(const_cast<RawSample*>(&s)))
      throw Error(Errc::kUnavailable, "DDS write failed on " + std::string(w_->get_topic()->get_name()));
  }
  bool WaitForAcked(int timeout_ms) override {
    return w_->wait_for_acknowledgments(
               eprosima::fastrtps::Duration_t(timeout_ms / 1000, (timeout_ms % 1000) * 1000000u)) ==
           eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
  }
  int Matched() const override {
    dds::PublicationMatchedStatus st;
    w_->get_publication_matched_status(st);
    return st.current_count;
  }
  uint64_t TotalMatched() const override {
    dds::PublicationMatchedStatus st;
    w_->get_publication_matched_status(st);
    return static_cast<uint64_t>(st.total_count);
  }

 private:
  // Fast DDS 2.9.1 leaves now and then a change of a keep-all volatile writer in its history after every
  // matched reader has acknowledged it: StatefulWriter::check_acked_status, finding every reader
  // acknowledged, moves its "notified up to" mark past changes it never reported as received by all, and only
  // that report removes a change. The change stays for the writer's life. Few, but the oldest one fixes the
  // first sequence number of every heartbeat, so each reader that joins is sent GAPs for the whole span
  // since, and the span grows with every sample: the scheduler's reply writer reached 7,700 after 20 minutes
  // of a 32-station week, its readers answering GAP after GAP (docs/operations.md §9.6). Before a write,
  // while every reader has acknowledged everything (so nothing unacknowledged can be lost), the history is
  // emptied, at most once a second: a sweep before every write tripled a request/reply round trip.
  void Sweep() {
    const auto now = std::chrono::steady_clock::now();
    if (now - swept_ < std::chrono::seconds(1)) return;
    if (w_->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(0, 0)) !=
        eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK)
      return;
    size_t removed = 0;
    w_->clear_history(&removed);
    swept_ = now;
  }

  dds::Publisher* pub_;
  dds::DataWriter* w_;
  const bool sweep_;  // keep-all and volatile (commands and streams)
  std::mutex mu_;     // the sweep's "all acknowledged" still true at its write
  std::chrono::steady_clock::time_point swept_{};
};

// The partition each writer publishes in, from discovery, so that a sample's publication handle names its
// writer's identity (RawInfo::writer_partition). Fast DDS 2.9 does not implement
// DataReader::get_matched_publication_data; its participant listener hears every remote writer before the
// writer is matched with a local reader (PDP::addWriterProxyData), so no sample arrives before its entry.
class WriterPartitions : public dds::DomainParticipantListener {
 public:
  explicit WriterPartitions(std::string own) : own_(std::move(own)) {}
  void SetOwnPrefix(const rtps::GuidPrefix_t& p) {
    std::lock_guard lk(mu_);
    own_prefix_ = p;
  }
  void on_publisher_discovery(dds::DomainParticipant*, rtps::WriterDiscoveryInfo&& info) override {
    std::lock_guard lk(mu_);
    if (info.status == rtps::WriterDiscoveryInfo::REMOVED_WRITER) {
      by_writer_.erase(info.info.guid());
      return;
    }
    const auto names = info.info.m_qos.m_partition.names();
    by_writer_[info.info.guid()] = names.size() == 1 ? names.front() : std::string();
  }
  void on_participant_discovery(dds::DomainParticipant*, rtps::ParticipantDiscoveryInfo&& info) override {
    using S = rtps::ParticipantDiscoveryInfo;
    std::lock_guard lk(mu_);
    if (info.status == S::DISCOVERED_PARTICIPANT) {
      participants_.insert(info.info.m_guid.guidPrefix);
    } else if (info.status == S::REMOVED_PARTICIPANT || info.status == S::DROPPED_PARTICIPANT) {
      participants_.erase(info.info.m_guid.guidPrefix);
      // A peer gone quiet, not one that said goodbye: killed, cut off, or too starved of CPU to announce
      // itself (docs/operations.md §11). Debug: every process of a cell says it of every kill, and a tool
      // that never set up its log would write it into its output (spdlog's default logger writes to stdout).
      if (info.status == S::DROPPED_PARTICIPANT)
        spdlog::debug("DDS: lost participant '{}': nothing heard from it within its lease",
                      info.info.m_participantName.to_string());
    }
  }
  int Participants() const {
    std::lock_guard lk(mu_);
    return static_cast<int>(participants_.size());
  }
  std::string Of(const rtps::InstanceHandle_t& publication) {
    const rtps::GUID_t g = rtps::iHandle2GUID(publication);
    std::lock_guard lk(mu_);
    if (g.guidPrefix == own_prefix_) return own_;  // this participant's own writers are not discovered
    auto it = by_writer_.find(g);
    return it == by_writer_.end() ? std::string() : it->second;
  }

 private:
  mutable std::mutex mu_;
  std::string own_;
  rtps::GuidPrefix_t own_prefix_;
  std::map<rtps::GUID_t, std::string> by_writer_;
  std::set<rtps::GuidPrefix_t> participants_;  // remote participants discovered and not lost
};

class FastReader : public RawReader, public dds::DataReaderListener {
 public:
  FastReader(dds::Subscriber* sub, RawCallback cb, WriterPartitions* writers)
      : sub_(sub), cb_(std::move(cb)), writers_(writers) {}
  void Attach(dds::DataReader* r) { r_ = r; }
  ~FastReader() override {
    if (!r_) return;  // never created (refused by access control): nothing to detach or delete
    r_->set_listener(nullptr);
    std::lock_guard lk(mu_);  // wait out a callback in flight
    sub_->delete_datareader(r_);
  }
  int Matched() const override {
    dds::SubscriptionMatchedStatus st;
    r_->get_subscription_matched_status(st);
    return st.current_count;
  }
  void on_data_available(dds::DataReader* reader) override {
    std::lock_guard lk(mu_);
    RawSample s;
    dds::SampleInfo info;
    while (reader->take_next_sample(&s, &info) == eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
      RawInfo ri;
      ri.valid = info.valid_data;
      if (ri.valid) ri.writer_partition = writers_->Of(info.publication_handle);
      cb_(s, ri);
    }
  }

 private:
  dds::Subscriber* sub_;
  dds::DataReader* r_ = nullptr;
  RawCallback cb_;
  WriterPartitions* writers_;
  std::mutex mu_;
};

constexpr uint32_t kReceiveBuffer = 16u << 20;

class FastBackend : public Backend {
 public:
  explicit FastBackend(const BackendOptions& o)
      : partition_(o.partition.empty() ? "id/unknown" : o.partition), writers_(partition_) {
    LogToStderr();
    auto* factory = dds::DomainParticipantFactory::get_instance();
    dds::DomainParticipantQos qos;  // built from scratch: no XML file in the CWD or env can widen it
    if (!o.profile_xml.empty())
      FromProfile(o, qos);
    else
      LoopbackOnly(qos, o.participants);
    qos.name(o.participant_name.empty() ? "cell" : o.participant_name);
    // A vanished process is noticed in ~3 s, not the 20 s default (station health, DESIGN §5).
    qos.wire_protocol().builtin.discovery_config.leaseDuration = eprosima::fastrtps::Duration_t(3, 0);
    qos.wire_protocol().builtin.discovery_config.leaseDuration_announcementperiod =
        eprosima::fastrtps::Duration_t(1, 0);
    // A new process (cellctl above all) is found as soon as it starts: ten announcements 10 ms apart
    // instead of five 100 ms apart. Measured with bus_discovery_bench (Fast DDS -> Fast DDS, first state
    // sample): median 840 ms -> 80 ms; a third of the runs still wait for the next 1 s announcement
    // (docs/architecture.md, "Discovery latency"). Nothing changes once the cell has settled.
    qos.wire_protocol().builtin.discovery_config.initial_announcements.count = 10;
    qos.wire_protocol().builtin.discovery_config.initial_announcements.period =
        eprosima::fastrtps::Duration_t(0, 10000000);
    if (!o.security.identity.empty()) Secure(o.security, qos);
    identity_ = o.security.identity;
    const int range = LoopbackRange(qos);  // before the gate wraps the transports
    // Every UDP transport (built-in loopback profile and the shipped LAN profiles) behind the gate.
    gate_ = std::make_shared<ReceiveGate>();
    for (auto& t : qos.transport().user_transports)
      if (std::dynamic_pointer_cast<frtps::UDPTransportDescriptor>(t))
        t = std::make_shared<GatedDescriptor>(t, gate_);
    {
      // One participant at a time per process, from choosing its slot until it has bound the slot's ports.
      SlotTable& slots = Slots();
      std::lock_guard lk(slots.mu);
      slot_ = ChooseSlot(o, range, qos, slots.held);
      NarrowPeers(qos, o, slot_);
      // The listener hears discovery only (no status: data goes to each reader's own listener).
      p_ = factory->create_participant(o.domain, qos, &writers_, dds::StatusMask::none());
      // Taken by p_, or, when it could not be made, kept by Fast DDS for the life of the process.
      if (slot_.number() >= 0) slots.held.insert(slot_.number());
    }
    if (!p_)
      throw Error(
          Errc::kUnavailable,
          "cannot create a DDS participant on domain " + std::to_string(o.domain) +
              (identity_.empty() ? ""
                                 : " as security identity '" + identity_ + "' (Fast DDS's log says why)"));
    writers_.SetOwnPrefix(p_->guid().guidPrefix);
    gate_->Open();  // create_participant has started reception: hand on what came before
    // docs/security.md, "Partitions": write in the identity's own partition, read every partition.
    dds::PublisherQos pq = dds::PUBLISHER_QOS_DEFAULT;
    pq.partition().push_back(partition_.c_str());
    dds::SubscriberQos sq = dds::SUBSCRIBER_QOS_DEFAULT;
    sq.partition().push_back("*");
    pub_ = p_->create_publisher(pq);
    sub_ = p_->create_subscriber(sq);
    if (!pub_ || !sub_) {
      p_->delete_contained_entities();
      factory->delete_participant(p_);
      throw Error(Errc::kInternal, "cannot create a DDS publisher or subscriber");
    }
  }

  ~FastBackend() override {
    p_->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(p_);  // releases its id and ports
    if (slot_.number() >= 0) {
      SlotTable& slots = Slots();
      std::lock_guard lk(slots.mu);
      slots.held.erase(slot_.number());
    }
  }

  std::string Name() const override { return "fastdds"; }
  int RemoteParticipants() const override { return writers_.Participants(); }
  int64_t OldestReceiveStartNs() const override { return gate_ ? gate_->OldestNs() : 0; }

  std::unique_ptr<RawWriter> CreateWriter(const std::string& topic, const TypeSupport& type,
                                          QosKind q) override {
    std::lock_guard lk(mu_);
    dds::Topic* t = TopicFor(topic, type);
    dds::DataWriterQos wq = dds::DATAWRITER_QOS_DEFAULT;
    ApplyQos(q, wq.reliability(), wq.durability(), wq.history());
    wq.endpoint().history_memory_policy = rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
    // Synchronous: write() sends on the caller's thread (fragments too); only repairs go through Fast DDS's
    // sending thread. With asynchronous publishing every sample waited there, and Fast DDS 2.9.1 deadlocks
    // that thread against a receive thread removing a reader of a volatile writer with a sample still
    // queued (eProsima #22339, fixed upstream in Dec 2024; docs/architecture.md, "A third Fast DDS 2.9.1
    // fault").
    wq.publish_mode().kind = dds::SYNCHRONOUS_PUBLISH_MODE;
    wq.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(0, 100000000);
    if (q == QosKind::kState || q == QosKind::kEvent) {
      wq.resource_limits().max_instances = 4096;
      wq.resource_limits().max_samples_per_instance = wq.history().depth;
      wq.resource_limits().max_samples = 4096 * wq.history().depth;
    }
    wq.properties().properties().emplace_back("dds.persistence.guid", NextPersistenceGuid());
    auto* w = pub_->create_datawriter(t, wq);
    if (!w && !identity_.empty())  // access control: the only reason a valid QoS is refused here
      throw Refused(identity_, "publish", topic);
    if (!w) throw Error(Errc::kInternal, "cannot create a DDS writer for " + topic);
    // The sweep is for the QoS the leftover changes come with, read from the QoS itself.
    const bool keep_all_volatile = wq.history().kind == dds::KEEP_ALL_HISTORY_QOS &&
                                   wq.durability().kind == dds::VOLATILE_DURABILITY_QOS;
    return std::make_unique<FastWriter>(pub_, w, keep_all_volatile);
  }

  std::unique_ptr<RawReader> CreateReader(const std::string& topic, const TypeSupport& type, QosKind q,
                                          RawCallback cb) override {
    std::lock_guard lk(mu_);
    dds::Topic* t = TopicFor(topic, type);
    dds::DataReaderQos rq = dds::DATAREADER_QOS_DEFAULT;
    ApplyQos(q, rq.reliability(), rq.durability(), rq.history());
    rq.endpoint().history_memory_policy = rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
    // A reliable reader asks a newly matched writer for its history 5 ms after matching, not 70: when the
    // writer's first data and heartbeat reached this side before the match (the two sides' endpoint
    // announcements cross), the first sample or reply came 70 ms late.
    rq.reliable_reader_qos().times.initialAcknackDelay = eprosima::fastrtps::Duration_t(0, 5000000);
    if (q == QosKind::kState || q == QosKind::kEvent) {
      rq.resource_limits().max_instances = 4096;
      rq.resource_limits().max_samples_per_instance = rq.history().depth;
      rq.resource_limits().max_samples = 4096 * rq.history().depth;
    }
    auto reader = std::make_unique<FastReader>(sub_, std::move(cb), &writers_);
    auto* r = sub_->create_datareader(t, rq, reader.get(), dds::StatusMask::data_available());
    if (!r && !identity_.empty()) throw Refused(identity_, "subscribe to", topic);
    if (!r) throw Error(Errc::kInternal, "cannot create a DDS reader for " + topic);
    reader->Attach(r);
    return reader;
  }

 private:
  // Fast DDS logs to stdout by default (its StdoutConsumer), where it would corrupt what a command prints
  // (`cellctl ... --json`): its log goes to stderr, the process's log, or nowhere (SilenceDdsLog).
  static void LogToStderr() {
    static std::once_flag once;
    std::call_once(once, [] {
      dds::Log::ClearConsumers();
      if (DdsLogSilenced()) return;
      auto consumer = std::make_unique<dds::StdoutErrConsumer>();
      consumer->stderr_threshold(dds::Log::Kind::Info);
      dds::Log::RegisterConsumer(std::move(consumer));
    });
  }

  // The participant profile named "cell" of a CELL_DDS_PROFILE file (deploy/dds/*.fastdds.xml). Loaded once
  // per process: Fast DDS refuses a second profile of the same name (a rejoin makes the backend again).
  static void FromProfile(const BackendOptions& o, dds::DomainParticipantQos& qos) {
    static std::mutex mu;
    static std::string loaded;
    std::lock_guard lk(mu);
    auto* factory = dds::DomainParticipantFactory::get_instance();
    const std::string what = "DDS profile " + o.profile_path;
    if (loaded.empty()) {
      if (factory->load_XML_profiles_string(o.profile_xml.c_str(), o.profile_xml.size()) !=
          eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK)
        throw Error(Errc::kInvalidArgument, what + ": not a loadable Fast DDS profile");
      loaded = o.profile_xml;
    } else if (loaded != o.profile_xml) {
      throw Error(Errc::kInvalidArgument, what + ": a process loads one Fast DDS profile only");
    }
    if (factory->get_participant_qos_from_profile("cell", qos) !=
        eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK)
      throw Error(Errc::kInvalidArgument, what + ": defines no <participant profile_name=\"cell\">");
  }

  // Fast DDS 2.9 numbers the participants of a process 0, 1, 2, ... and never reuses a number, and a
  // participant's unicast ports follow its number (7410 + 250·domain + 2·n), while peers probe only the first
  // `range` (maxInitialPeersRange, config::DdsParticipants). A process that has rejoined the bus that many
  // times (a VM paused again and again)
  // would get ports no peer probes, and two such processes would never find each other; 4x as many
  // participants in bus_test showed it. So the backend takes the lowest slot whose ports no process (of
  // either stack: Cyclone uses the same formula) has bound, above the host services' (a host service takes
  // its own, slots.h), and a fresh random GUID prefix, because Fast DDS
  // derives the prefix from the number and a rejoin must look like a stranger to every peer.
  // Free ports are not enough: Fast DDS keeps the number of a participant it failed to make (a refused
  // identity: RTPSDomainImpl::createParticipant returns before releasing it) and refuses it ever after
  // ("RTPSParticipant with the same ID already exists"). Hence `held`, the slots this process gave Fast DDS
  // and not yet got back. Returns the slot, held; none when all are taken (Fast DDS then numbers it).
  // Fast DDS 2.9 gives each writer of a participant whose GUID prefix was chosen (ChooseSlot) a persistence
  // GUID: the prefix Fast DDS would have derived (host, process, participant number) and the writer's entity
  // id. After a rejoin on the same slot both are the same again. A reader that lost the old writer by lease
  // keeps the last sequence number it had from it under that GUID (RTPSReader::history_record, kept on
  // purpose "removed by lease") and starts the new writer's proxy there: it drops the new writer's samples
  // as duplicates until its count passes the old one's. Seen in a Fast DDS week: the scheduler deaf to a
  // station's liveness for 47 minutes, the program store to an interpreter's requests (docs/operations.md
  // §9.6). So each writer gets a persistence GUID of its own, under this participant's random prefix.
  std::string NextPersistenceGuid() {
    const uint32_t n = ++writers_made_;
    rtps::GUID_t g;
    g.guidPrefix = p_->guid().guidPrefix;
    g.entityId.value[0] = static_cast<rtps::octet>(n >> 16);
    g.entityId.value[1] = static_cast<rtps::octet>(n >> 8);
    g.entityId.value[2] = static_cast<rtps::octet>(n);
    g.entityId.value[3] = 0x42;  // vendor-specific kind: never a real endpoint's id
    std::ostringstream out;
    out << g;
    return out.str();
  }

  static slots::Slot ChooseSlot(const BackendOptions& o, int range, dds::DomainParticipantQos& qos,
                                const std::set<int>& held) {
    slots::Slot slot = slots::Choose(o, range, std::vector<int>(held.begin(), held.end()), true);
    if (slot.number() < 0) return slot;
    qos.wire_protocol().participant_id = slot.number();
    std::random_device rd;
    auto& prefix = qos.wire_protocol().prefix;
    prefix.value[0] = 0x01;  // eProsima's vendor id, as Fast DDS writes it
    prefix.value[1] = 0x0f;
    for (size_t i = 2; i < prefix.size; ++i) prefix.value[i] = static_cast<rtps::octet>(rd());
    return slot;
  }
  struct SlotTable {
    std::mutex mu;
    std::set<int> held;
  };
  static SlotTable& Slots() {
    static SlotTable table;  // every domain: Fast DDS numbers the participants of a process, not of a domain
    return table;
  }
  // DDS Security 1.1 builtin plugins (docs/security.md); the governance and permissions are the signed .p7s.
  static void Secure(const SecurityFiles& f, dds::DomainParticipantQos& qos) {
    auto& props = qos.properties().properties();
    auto file = [](const std::string& path) { return "file://" + path; };
    props.emplace_back("dds.sec.auth.plugin", "builtin.PKI-DH");
    props.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_ca", file(f.ca));
    props.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_certificate", file(f.certificate));
    props.emplace_back("dds.sec.auth.builtin.PKI-DH.private_key", file(f.key));
    if (!f.crl.empty()) props.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_crl", file(f.crl));
    props.emplace_back("dds.sec.access.plugin", "builtin.Access-Permissions");
    props.emplace_back("dds.sec.access.builtin.Access-Permissions.permissions_ca", file(f.ca));
    props.emplace_back("dds.sec.access.builtin.Access-Permissions.governance", file(f.governance));
    props.emplace_back("dds.sec.access.builtin.Access-Permissions.permissions", file(f.permissions));
    props.emplace_back("dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC");
  }

  // The peer range of the process's UDP transport: the ports its peers can have (a LAN profile's own
  // maxInitialPeersRange, the loopback profile's config::DdsParticipants).
  static int LoopbackRange(const dds::DomainParticipantQos& qos) {
    int range = 4;  // Fast DDS's default
    for (auto& t : qos.transport().user_transports)
      if (auto udp = std::dynamic_pointer_cast<frtps::UDPTransportDescriptor>(t))
        range = std::max<int>(range, static_cast<int>(udp->maxInitialPeersRange));
    return range;
  }

  static void LoopbackOnly(dds::DomainParticipantQos& qos, int participants) {
    // DESIGN §3: loopback, unicast discovery, no multicast, no shared memory, peers sized to the cell.
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    udp->interfaceWhiteList.emplace_back("127.0.0.1");
    udp->maxInitialPeersRange = static_cast<uint32_t>(participants);
    // A newcomer joining a large cell is answered by every participant at once: with the kernel's default
    // 208 kB receive buffer, a 68-process cell dropped 34,000 datagrams while one process joined, and the
    // retransmissions took seconds; with 4 MB a 32-station `cellctl up` still dropped about 200,000, with
    // 16 MB none. The kernel caps this at net.core.rmem_max (deploy/install raises it).
    udp->receiveBufferSize = kReceiveBuffer;
    qos.transport().use_builtin_transports = false;
    qos.transport().user_transports.push_back(udp);
    rtps::Locator_t lo;
    lo.kind = LOCATOR_KIND_UDPv4;
    eprosima::fastrtps::rtps::IPLocator::setIPv4(lo, 127, 0, 0, 1);
    qos.wire_protocol().builtin.metatrafficUnicastLocatorList.push_back(lo);
    qos.wire_protocol().builtin.initialPeersList.push_back(lo);
    qos.wire_protocol().default_unicast_locator_list.push_back(lo);
  }

  // An initial peer without a port stands for every slot of that host (maxInitialPeersRange);
  // slots::AnnouncedSlots says when a participant announces itself to that host's first few slots only (a
  // client of the host services, a station's process and another host): the peer becomes those slots.
  static void NarrowPeers(dds::DomainParticipantQos& qos, const BackendOptions& o, const slots::Slot& slot) {
    rtps::LocatorList_t peers;
    for (const auto& l : qos.wire_protocol().builtin.initialPeersList) {
      const auto announced =
          l.port == 0 ? slots::AnnouncedSlots(o, slots::IsAnotherHost(rtps::IPLocator::ip_to_string(l)), slot)
                      : std::vector<int>{};
      if (announced.empty()) {
        peers.push_back(l);
        continue;
      }
      for (int slot : announced) {
        rtps::Locator_t peer = l;
        peer.port = static_cast<uint32_t>(slots::DiscoveryPort(o.domain, slot));
        peers.push_back(peer);
      }
    }
    qos.wire_protocol().builtin.initialPeersList = peers;
  }

  dds::Topic* TopicFor(const std::string& name, const TypeSupport& type) {
    auto it = topics_.find(name);
    if (it != topics_.end()) {
      if (it->second->get_type_name() != type.name)
        throw Error(Errc::kInvalidArgument,
                    "topic " + name + " already used with type " + it->second->get_type_name());
      return it->second;
    }
    if (!types_.count(type.name)) {
      dds::TypeSupport ts(new CdrType(type));
      if (ts.register_type(p_) != eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK)
        throw Error(Errc::kInternal, "cannot register DDS type " + type.name);
      types_.insert(type.name);
    }
    dds::Topic* t = p_->create_topic(name, type.name, dds::TOPIC_QOS_DEFAULT);
    if (!t) throw Error(Errc::kInternal, "cannot create DDS topic " + name);
    topics_[name] = t;
    return t;
  }

  std::mutex mu_;
  std::string partition_;
  std::shared_ptr<ReceiveGate> gate_;  // shared with the transports Fast DDS made from it
  WriterPartitions writers_;  // declared before p_: the participant (deleted in ~FastBackend) uses it
  dds::DomainParticipant* p_ = nullptr;
  slots::Slot slot_;      // the participant id, held; none: Fast DDS chose it
  std::string identity_;  // DDS Security identity; empty: unsecured
  dds::Publisher* pub_ = nullptr;
  dds::Subscriber* sub_ = nullptr;
  std::map<std::string, dds::Topic*> topics_;
  std::set<std::string> types_;
  uint32_t writers_made_ = 0;  // under mu_: NextPersistenceGuid
};

}  // namespace

namespace {
std::atomic<bool> silenced{false};
}  // namespace

void SilenceDdsLog() {
  silenced = true;
}
bool DdsLogSilenced() {
  return silenced;
}

std::unique_ptr<Backend> MakeFastDdsBackend(const BackendOptions& opts) {
  static std::once_flag checked;
  std::call_once(checked, [] {
    if (!FastDdsLeaseCheckMended())
      spdlog::warn(
          "Fast DDS runs its own lease check, not the bus's (a Fast DDS other than 2.9, or not exported): "
          "a peer's leaving can abort or deadlock this process (docs/architecture.md, \"The bus's lease "
          "check\")");
  });
  return std::make_unique<FastBackend>(opts);
}

}  // namespace cell::bus
