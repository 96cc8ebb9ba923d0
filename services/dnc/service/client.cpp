// cell-dnc's public face: the transfer request and the lines' state (docs/dnc.md "On the bus").
#include "cell/dnc/client.h"

#include <algorithm>

#include "cell/bus/topics.h"

namespace cell::dnc {

std::string_view OpName(cell::DncOp op) {
  switch (op) {
    case cell::DNC_SEND:
      return "send";
    case cell::DNC_RECEIVE:
      return "receive";
    case cell::DNC_DRIP:
      return "drip";
    case cell::DNC_STATUS:
      return "status";
    case cell::DNC_READ:
      return "read";
    case cell::DNC_WRITE:
      return "write";
  }
  return "?";
}

std::string_view StateName(cell::DncState s) {
  switch (s) {
    case cell::DNC_IDLE:
      return "idle";
    case cell::DNC_SENDING:
      return "sending";
    case cell::DNC_RECEIVING:
      return "receiving";
    case cell::DNC_DRIPPING:
      return "dripping";
    case cell::DNC_READING:
      return "reading";
    case cell::DNC_WRITING:
      return "writing";
  }
  return "?";
}

nlohmann::json StatusJson(const cell::DncStatus& s) {
  return {{"station", s.station().to_string()},
          {"dnc", true},
          {"device", s.device().to_string()},
          {"state", StateName(s.state())},
          {"program", s.program().to_string()},
          {"bytes", s.bytes()},
          {"total", s.total()},
          {"seconds", s.seconds()},
          {"rate", s.rate()},
          {"stalls", s.stalls()},
          {"stopped_s", s.stopped_s()},
          {"transfers", s.transfers()},
          {"errors", s.errors()},
          {"last_error", s.last_error().to_string()},
          {"failed", s.failed()}};
}

Client::Client(bus::Participant& p, const std::string& station)
    : station_(station), client_(p, bus::topics::StationDnc(station)) {}

cell::DncReply Client::Run(cell::DncOp op, const std::string& node, const std::string& name,
                           const std::function<std::string()>& gone) {
  cell::DncRequest req;
  req.station(station_);
  req.op(op);
  req.node(node);
  req.name(name);
  // The reply comes when the transfer has ended: no deadline of our own (the line's own timeouts end a
  // transfer that stalls); a request re-sent each second is answered once, from the server's cache.
  constexpr bus::Millis kNoDeadline{std::chrono::hours(24 * 365)};
  cell::DncReply rep =
      client_.Call(req, op == cell::DNC_STATUS ? bus::Millis(10000) : kNoDeadline, bus::Millis(1000), gone);
  bus::ThrowIfError(rep);
  return rep;
}

cell::DncReply Client::Record(cell::DncOp op, const std::string& holder, const std::string& record,
                              bus::Millis timeout) {
  cell::DncRequest req;
  req.station(station_);
  req.op(op);
  req.name(holder.substr(0, 128));
  req.data(std::vector<uint8_t>(record.begin(), record.end()));
  cell::DncReply rep = client_.Call(req, timeout);
  bus::ThrowIfError(rep);
  return rep;
}

std::map<std::string, cell::DncStatus> Statuses(bus::Participant& p, const std::vector<std::string>& expect,
                                                bus::Millis timeout) {
  std::map<std::string, cell::DncStatus> out;
  bus::Reader<cell::DncStatus> r(p, bus::topics::kDncStatus, bus::QosKind::kState);
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  auto all_heard = [&] {
    return std::all_of(expect.begin(), expect.end(), [&](const std::string& s) { return out.count(s) > 0; });
  };
  while (!all_heard()) {
    auto left = std::chrono::duration_cast<bus::Millis>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    auto s = r.Take(left);
    if (!s) break;
    out[s->station().to_string()] = *s;
  }
  while (auto s = r.Take(bus::Millis(0))) out[s->station().to_string()] = *s;  // what else has arrived
  return out;
}

}  // namespace cell::dnc
