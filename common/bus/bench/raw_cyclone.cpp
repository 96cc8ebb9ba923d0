// The ping-pong written directly on Cyclone DDS 0.10's C API: the baseline the bus's Cyclone glue is
// measured against. Same configuration as that glue's built-in profile (127.0.0.1 only, unicast discovery
// with peer 127.0.0.1, no multicast, no shared memory, 64 MB writer history watermarks), same QoS (reliable,
// volatile, keep-all), and the idlc-generated C type with Cyclone's own serializer: what a C program would
// write, where the bus carries Fast CDR bytes under the same type (reference/cyclone-rawcdr.md).
#include <cstring>
#include <stdexcept>

#include <dds/dds.h>

#include "pingpong.h"
#include "program_store.h"  // idlc's C type and descriptor (idl/c)

namespace cell::bus::bench {
namespace {

// As the bus's kLoopbackXml + kCellXml (common/bus/src/cyclone_backend.cpp), so both run on one transport.
constexpr const char* kConfig =
    "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface address=\"127.0.0.1\"/>"
    "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
    "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>32</MaxAutoParticipantIndex>"
    "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain></CycloneDDS>"
    "<CycloneDDS><Domain Id=\"any\"><Internal><Watermarks><WhcHighInit>64 MB</WhcHighInit>"
    "<WhcHigh>64 MB</WhcHigh><WhcAdaptive>false</WhcAdaptive></Watermarks></Internal></Domain></CycloneDDS>";

class RawCyclone : public PingPong {
 public:
  RawCyclone(bool pinger, int domain, OnReceive on_receive) : on_receive_(std::move(on_receive)) {
    domain_ = dds_create_domain(static_cast<dds_domainid_t>(domain), kConfig);
    if (domain_ < 0) throw std::runtime_error("raw Cyclone: cannot create the domain");
    pp_ = dds_create_participant(static_cast<dds_domainid_t>(domain), nullptr, nullptr);
    if (pp_ < 0) throw std::runtime_error("raw Cyclone: cannot create a participant");
    dds_entity_t out =
        dds_create_topic(pp_, &cell_ProgramRequest_desc, pinger ? kPingTopic : kPongTopic, nullptr, nullptr);
    dds_entity_t in =
        dds_create_topic(pp_, &cell_ProgramRequest_desc, pinger ? kPongTopic : kPingTopic, nullptr, nullptr);
    dds_qos_t* q = dds_create_qos();
    dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(10));
    dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
    dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
    w_ = dds_create_writer(pp_, out, q, nullptr);
    dds_listener_t* l = dds_create_listener(this);
    dds_lset_data_available(l, &RawCyclone::DataAvailable);
    r_ = dds_create_reader(pp_, in, q, l);
    dds_delete_listener(l);
    dds_delete_qos(q);
    if (out < 0 || in < 0 || w_ < 0 || r_ < 0)
      throw std::runtime_error("raw Cyclone: cannot create the endpoints");
  }
  ~RawCyclone() override {
    dds_delete(pp_);
    dds_delete(domain_);
  }

  bool Matched() override {
    dds_publication_matched_status_t ws;
    dds_subscription_matched_status_t rs;
    if (dds_get_publication_matched_status(w_, &ws) < 0 || dds_get_subscription_matched_status(r_, &rs) < 0)
      return false;
    return ws.current_count > 0 && rs.current_count > 0;
  }

  void Send(uint32_t seq, const uint8_t* data, size_t size) override {
    cell_ProgramRequest msg;
    std::memset(&msg, 0, sizeof msg);
    msg.chunk_index = seq;
    msg.data._buffer = const_cast<uint8_t*>(data);
    msg.data._length = msg.data._maximum = static_cast<uint32_t>(size);
    msg.data._release = false;
    if (dds_write(w_, &msg) < 0) throw std::runtime_error("raw Cyclone: write failed");
  }

 private:
  static void DataAvailable(dds_entity_t reader, void* arg) {
    auto* self = static_cast<RawCyclone*>(arg);
    void* samples[1] = {nullptr};
    dds_sample_info_t info[1];
    while (dds_take(reader, samples, info, 1, 1) > 0) {
      const auto* s = static_cast<const cell_ProgramRequest*>(samples[0]);
      if (info[0].valid_data) self->on_receive_(s->chunk_index, s->data._buffer, s->data._length);
      dds_return_loan(reader, samples, 1);
      samples[0] = nullptr;
    }
  }

  OnReceive on_receive_;
  dds_entity_t domain_ = 0, pp_ = 0, w_ = 0, r_ = 0;
};

}  // namespace

std::unique_ptr<PingPong> MakeRawCyclone(bool pinger, int domain, PingPong::OnReceive on_receive) {
  return std::make_unique<RawCyclone>(pinger, domain, std::move(on_receive));
}

}  // namespace cell::bus::bench
