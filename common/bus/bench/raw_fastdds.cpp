// The ping-pong written directly on Fast DDS 2.9's DDS API: the baseline the bus is measured against. It
// uses what the bus's Fast DDS glue configures (UDPv4 on 127.0.0.1 only, unicast discovery, no shared memory,
// 3 s lease, reliable/volatile/keep-all, synchronous publishing, 100 ms heartbeats) and the type support a
// code generator would write: Fast CDR straight into the payload, sample taken into a reused object.
#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>

#include <cstring>
#include <mutex>

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include "cell/idl/program_store.h"
#include "pingpong.h"

namespace cell::bus::bench {
namespace {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;
using eprosima::fastrtps::types::ReturnCode_t;

class RequestType : public dds::TopicDataType {
 public:
  RequestType() {
    setName("cell::ProgramRequest");
    m_typeSize = static_cast<uint32_t>(cell::ProgramRequest::getMaxCdrSerializedSize() + 4);
    m_isGetKeyDefined = false;
  }
  bool serialize(void* data, rtps::SerializedPayload_t* payload) override {
    eprosima::fastcdr::FastBuffer buf(reinterpret_cast<char*>(payload->data), payload->max_size);
    eprosima::fastcdr::Cdr ser(buf, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
    payload->encapsulation = ser.endianness() == eprosima::fastcdr::Cdr::BIG_ENDIANNESS ? CDR_BE : CDR_LE;
    ser.serialize_encapsulation();
    static_cast<cell::ProgramRequest*>(data)->serialize(ser);
    payload->length = static_cast<uint32_t>(ser.getSerializedDataLength());
    return true;
  }
  bool deserialize(rtps::SerializedPayload_t* payload, void* data) override {
    eprosima::fastcdr::FastBuffer buf(reinterpret_cast<char*>(payload->data), payload->length);
    eprosima::fastcdr::Cdr des(buf, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
    des.read_encapsulation();
    static_cast<cell::ProgramRequest*>(data)->deserialize(des);
    return true;
  }
  std::function<uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data] {
      return static_cast<uint32_t>(
          cell::ProgramRequest::getCdrSerializedSize(*static_cast<cell::ProgramRequest*>(data)) + 4);
    };
  }
  void* createData() override { return new cell::ProgramRequest(); }
  void deleteData(void* data) override { delete static_cast<cell::ProgramRequest*>(data); }
  bool getKey(void*, rtps::InstanceHandle_t*, bool) override { return false; }
};

class RawFast : public PingPong, public dds::DataReaderListener {
 public:
  RawFast(bool pinger, int domain, OnReceive on_receive) : on_receive_(std::move(on_receive)) {
    dds::DomainParticipantQos qos;
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    udp->interfaceWhiteList.emplace_back("127.0.0.1");
    udp->maxInitialPeersRange = 32;
    qos.transport().use_builtin_transports = false;
    qos.transport().user_transports.push_back(udp);
    rtps::Locator_t lo;
    lo.kind = LOCATOR_KIND_UDPv4;
    eprosima::fastrtps::rtps::IPLocator::setIPv4(lo, 127, 0, 0, 1);
    qos.wire_protocol().builtin.metatrafficUnicastLocatorList.push_back(lo);
    qos.wire_protocol().builtin.initialPeersList.push_back(lo);
    qos.wire_protocol().default_unicast_locator_list.push_back(lo);
    qos.wire_protocol().builtin.discovery_config.leaseDuration = eprosima::fastrtps::Duration_t(3, 0);
    qos.wire_protocol().builtin.discovery_config.leaseDuration_announcementperiod =
        eprosima::fastrtps::Duration_t(1, 0);
    p_ = dds::DomainParticipantFactory::get_instance()->create_participant(domain, qos);
    if (!p_) throw std::runtime_error("raw Fast DDS: cannot create a participant");
    dds::TypeSupport ts(new RequestType());
    ts.register_type(p_);
    dds::Topic* out =
        p_->create_topic(pinger ? kPingTopic : kPongTopic, ts.get_type_name(), dds::TOPIC_QOS_DEFAULT);
    dds::Topic* in =
        p_->create_topic(pinger ? kPongTopic : kPingTopic, ts.get_type_name(), dds::TOPIC_QOS_DEFAULT);
    pub_ = p_->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
    sub_ = p_->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
    dds::DataWriterQos wq = dds::DATAWRITER_QOS_DEFAULT;
    wq.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
    wq.durability().kind = dds::VOLATILE_DURABILITY_QOS;
    wq.history().kind = dds::KEEP_ALL_HISTORY_QOS;
    wq.endpoint().history_memory_policy = rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
    wq.publish_mode().kind = dds::SYNCHRONOUS_PUBLISH_MODE;
    wq.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(0, 100000000);
    w_ = pub_->create_datawriter(out, wq);
    dds::DataReaderQos rq = dds::DATAREADER_QOS_DEFAULT;
    rq.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
    rq.durability().kind = dds::VOLATILE_DURABILITY_QOS;
    rq.history().kind = dds::KEEP_ALL_HISTORY_QOS;
    rq.endpoint().history_memory_policy = rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
    r_ = sub_->create_datareader(in, rq, this, dds::StatusMask::data_available());
    if (!w_ || !r_) throw std::runtime_error("raw Fast DDS: cannot create the writer or reader");
  }
  ~RawFast() override {
    r_->set_listener(nullptr);
    { std::lock_guard lk(mu_); }  // a callback in flight finishes
    p_->delete_contained_entities();
    dds::DomainParticipantFactory::get_instance()->delete_participant(p_);
  }

  bool Matched() override {
    dds::PublicationMatchedStatus ws;
    dds::SubscriptionMatchedStatus rs;
    w_->get_publication_matched_status(ws);
    r_->get_subscription_matched_status(rs);
    return ws.current_count > 0 && rs.current_count > 0;
  }

  void Send(uint32_t seq, const uint8_t* data, size_t size) override {
    std::lock_guard lk(send_mu_);
    out_.chunk_index(seq);
    out_.data().assign(data, data + size);
    if (w_->write(&out_) != true) throw std::runtime_error("raw Fast DDS: write failed");
  }

  void on_data_available(dds::DataReader* reader) override {
    std::lock_guard lk(mu_);
    dds::SampleInfo info;
    while (reader->take_next_sample(&in_, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data) on_receive_(in_.chunk_index(), in_.data().data(), in_.data().size());
  }

 private:
  OnReceive on_receive_;
  dds::DomainParticipant* p_ = nullptr;
  dds::Publisher* pub_ = nullptr;
  dds::Subscriber* sub_ = nullptr;
  dds::DataWriter* w_ = nullptr;
  dds::DataReader* r_ = nullptr;
  std::mutex mu_, send_mu_;
  cell::ProgramRequest in_, out_;
};

}  // namespace

std::unique_ptr<PingPong> MakeRawFastDds(bool pinger, int domain, PingPong::OnReceive on_receive) {
  return std::make_unique<RawFast>(pinger, domain, std::move(on_receive));
}

}  // namespace cell::bus::bench
