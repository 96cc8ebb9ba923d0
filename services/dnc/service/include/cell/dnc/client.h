// cell-dnc's public face (docs/dnc.md "On the bus"): what cellctl (and any other process) calls. A
// transfer is one request on the station's own topic, answered when it has ended; the line's state is on
// cell/dnc/status, which every cell-dnc writes while it lives.
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/idl/dnc.h"

namespace cell::dnc {

std::string_view OpName(cell::DncOp op);       // "send", "receive", "drip", "status", "read", "write"
std::string_view StateName(cell::DncState s);  // "idle", "sending", "receiving", "dripping", "reading", ...

// One line's state as `cellctl dnc status --json` prints it: {station, dnc, device, state, program, bytes,
// seconds, rate, stalls, stopped_s, transfers, errors, last_error}.
nlohmann::json StatusJson(const cell::DncStatus& s);

class Client {
 public:
  Client(bus::Participant& p, const std::string& station);
  // Runs `op` on the station's line and waits until it has ended, however long that takes (a drip feed
  // runs for hours), unless `gone` says the station's cell-dnc is gone. Throws cell::Error with the
  // service's one-line reason.
  cell::DncReply Run(cell::DncOp op, const std::string& node, const std::string& name,
                     const std::function<std::string()>& gone);
  // A program's READ or WRITE (docs/dnc.md "Okuma READ/WRITE"), answered at once (a READ: started, or done
  // with the record in `data`) within `timeout`. `holder` names the run. Throws cell::Error: the service's
  // refusal or failure, kUnavailable/kTimeout when no cell-dnc answers.
  cell::DncReply Record(cell::DncOp op, const std::string& holder, const std::string& record,
                        bus::Millis timeout);

 private:
  std::string station_;
  bus::Client<cell::DncRequest, cell::DncReply> client_;
};

// The state of every line whose cell-dnc runs (cell/dnc/status), by station: waits up to `timeout` for
// each station of `expect`, less when they have all spoken.
std::map<std::string, cell::DncStatus> Statuses(bus::Participant& p, const std::vector<std::string>& expect,
                                                bus::Millis timeout);

}  // namespace cell::dnc
