// Files a program writes (KT-APL OIF/MSG,NAM, OPF, FWR, CLF, RCP; manual ch. 7 ln 7886-8356): the open file
// is kept by the run; at its close the whole file goes to the inspection writer, which answers once it is on
// disk (fsync), and then to the program store in the node's namespace as a new revision (declared in the
// station's dialect, type `inspection` for OIF files, else `data`). Only then is the program's completion
// flag (L1050) set. This is the one path for every file a program writes on a station; DLF deletes from the
// station's namespace and an append (A/) continues the stored file. A writer or store
// that is not on the bus is waited for; one that refuses fails the operation with its reason.
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
  // `program`: the program's place in the dispatch (1, 2, ...; repeats counted), part of every idempotency
  // key. `checkpoint` throws when the run is cancelled or the station stops (called while waiting).
  ProgramFiles(std::string station, std::string dialect, std::int32_t dispatch_id, int program, StationIo& io,
               Clock& clock, std::function<void()> checkpoint, Clock::Duration writer_wait);
  interp::FileResult Apply(const interp::Canon& op);

 private:
  struct Closed {
    std::string text;
    bool inspection = false;  // an OIF / MSG,NAM file (its copies too)
  };
  interp::FileResult Store(const std::string& node, const std::string& name, const Closed& file);
  interp::FileResult RemoteCopy(const std::string& args);
  interp::FileResult Delete(const std::string& name);
  interp::FileResult Patiently(const char* who, const char* failed, const std::function<bool()>& attempt);
  std::string NextKey();  // the idempotency key of the next store or delete

  const std::string station_;
  const std::string dialect_;
  const std::int32_t dispatch_id_;
  const int program_;
  StationIo& io_;
  Clock& clock_;
  std::function<void()> checkpoint_;
  const Clock::Duration writer_wait_;
  std::string open_;                      // the open file's name ("" = none)
  Closed file_;                           // its lines so far
  std::map<std::string, Closed> closed_;  // files this run closed, by upper-case name (RCP, CPY)
  int stores_ = 0;                        // stores so far (the idempotency key's sequence)
};

}  // namespace cell::station
