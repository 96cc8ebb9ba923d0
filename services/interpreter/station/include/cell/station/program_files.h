// Files a program writes (KT-APL OIF/MSG,NAM, OPF, FWR, CLF, RCP; manual ch. 7 ln 7886-8356): the open file
// is kept by the run; at its close the whole file goes to the inspection writer, which answers once it is on
// disk (fsync). Only then is the program's completion flag (L1050) set. This is the one path for every file
// a program writes on a station. A writer that is not on the bus is waited for (the run shows it in its
// status); one that refuses fails the operation with its reason.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>

#include "cell/interp/run.h"
#include "cell/station/clock.h"

namespace cell::station {

class StationIo;

class ProgramFiles {
 public:
  // `checkpoint` throws when the run is cancelled or the station stops (called while waiting).
  ProgramFiles(std::string station, std::int32_t dispatch_id, StationIo& io, Clock& clock,
               std::function<void()> checkpoint, Clock::Duration writer_wait);
  interp::FileResult Apply(const interp::Canon& op);

 private:
  interp::FileResult Store(const std::string& node, const std::string& name, const std::string& text);
  interp::FileResult RemoteCopy(const std::string& args);

  const std::string station_;
  const std::int32_t dispatch_id_;
  StationIo& io_;
  Clock& clock_;
  std::function<void()> checkpoint_;
  const Clock::Duration writer_wait_;
  std::string open_;                           // the open file's name ("" = none)
  std::string text_;                           // its lines so far
  std::map<std::string, std::string> closed_;  // files this run closed, by upper-case name (RCP, CPY)
};

}  // namespace cell::station
