// The seam of bus_pingpong_bench: one ping-pong endpoint per implementation (the bus on either vendor, or
// the vendor's own API), so the driver times every implementation the same way. Two command topics,
// "bench/ping" and "bench/pong", carry cell::ProgramRequest samples (its octet sequence is the payload);
// QoS everywhere: reliable, volatile, keep-all (the bus's kCommand).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace cell::bus::bench {

inline constexpr const char* kPingTopic = "bench/ping";
inline constexpr const char* kPongTopic = "bench/pong";

class PingPong {
 public:
  // seq and the payload of a received sample; called on the implementation's receive thread.
  using OnReceive = std::function<void(uint32_t seq, const uint8_t* data, size_t size)>;
  virtual ~PingPong() = default;
  // Both topics matched: our writer has a reader and our reader a writer.
  virtual bool Matched() = 0;
  virtual void Send(uint32_t seq, const uint8_t* data, size_t size) = 0;
};

// pinger: writes kPingTopic, reads kPongTopic; ponger the other way round.
std::unique_ptr<PingPong> MakeRawFastDds(bool pinger, int domain, PingPong::OnReceive on_receive);
std::unique_ptr<PingPong> MakeRawCyclone(bool pinger, int domain, PingPong::OnReceive on_receive);

}  // namespace cell::bus::bench
