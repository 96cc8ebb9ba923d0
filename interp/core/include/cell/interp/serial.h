// The control's serial channel (Okuma User Task READ/WRITE, ln 8075-8109): a capability an Environment may
// have. The station's environment has it (its [serial] line, through cell-dnc: docs/dnc.md "Okuma
// READ/WRITE"); without it (offline `cell-interp`) the dialect keeps its virtual channel, the run's RS232C
// parameter and a file_write op. A dialect asks `dynamic_cast<SerialChannel*>(env)`.
#pragma once

#include <string>

namespace cell::interp {

class SerialChannel {
 public:
  virtual ~SerialChannel() = default;
  // `error`: the line failed or refused (the run alarms with it); otherwise the record, without its end code.
  struct Result {
    std::string record;
    std::string error;
  };
  // Blocks until a record arrives; throws what ends the run (a cancel, a stop).
  virtual Result SerialRead() = 0;
  // Returns when the record and its end code are on the line; throws what ends the run.
  virtual Result SerialWrite(const std::string& record) = 0;
};

}  // namespace cell::interp
