// A run of a part program: what every dialect's executor implements and every caller (the offline CLI, the
// station service, tests) drives. Dialects are chosen through the registry (cell/interp/interp.h).
//
//   RunOptions opt; opt.program_name = "PUMP341"; opt.program_text = text;
//   auto run = FindDialect("ktapl")->StartRun(opt);   // or cell::interp::StartRun with opt.dialect
//   for (Step s;;) {
//     run->NextInto(s);                                  // blocks only inside Environment callbacks
//     if (s.kind == Step::kCanon) publish(s.canon);
//     else if (s.kind == Step::kEnd) break;              // ran to its end
//     else { report(s.diag); break; }                    // kError: the run stops at the first error
//   }
//
// Memory does not grow with program length: the program text is scanned block by block, and a mapped
// program (ProgramText::MapFile) gives back the pages the run has passed.
#pragma once

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cell/interp/canon.h"
#include "cell/interp/program_text.h"
#include "cell/tooltable/tooltable.h"

namespace cell::interp {

// A program error, printed as PROGRAM:LINE:COL: error: [ALARM] text (brackets omitted when alarm is empty).
struct Diagnostic {
  std::string program;
  int line = 0;  // 1-based
  int col = 0;   // 1-based
  std::string alarm;
  std::string text;
  std::string Format() const;
};

// A probe move: toward contact (KT-APL G22, make) or away from it (G23, break), a straight move from `from`
// to `to` (machine coordinates, mm / deg) at `feed` mm/min (0: the machine's probe feed). The positions
// include the probe's length compensation `length` in Z (mm), measured to the stylus ball's tip: the tip is
// at z - length, the ball's centre one ball radius above it.
struct ProbeMove {
  bool make = true;
  AxisArray from{}, to{};
  double feed = 0;
  double length = 0;
};

// Result of a probe move (contact or break).
struct ProbeResult {
  bool already = false;  // already in the requested state at the start: no motion
  bool event = false;    // the contact (break) happened
  AxisArray at{};        // machine position where the event happened (mm / deg)
};

// What the machine's file system said about a file effect.
struct FileResult {
  bool done = true;   // finished, durably: the program's completion flag (KT-APL L1050-L1054) may be set
  std::string error;  // the device's message when it failed ("FILE ALREADY EXISTS", "SOURCE FILE READ ERROR")
};

// Queue busters: everything whose result the program reads. The offline CLI answers at once; the service
// answers over DDS (a blocking call is fine).
class Environment {
 public:
  virtual ~Environment() = default;
  // A probe move; offline without a part model it never trips (the move runs to its end).
  virtual ProbeResult Probe(const ProbeMove& move);
  // Waits until the discrete inputs match `spec` (the dialect's form). Offline: at once.
  virtual void WaitInputs(const std::string& spec) { (void)spec; }
  // Machine state the program may read (KT-APL L3000-L3999, Okuma system variables, ...), by the dialect's
  // own name ("L3020"); nullopt = not known.
  virtual std::optional<double> SystemVariable(const std::string& name) {
    (void)name;
    return std::nullopt;
  }
  // G38 broken-tool check of the tool in the spindle where the machine stands (`flutes`: the edges to see in
  // one revolution, 0 for a single-point tool): true when the tool is whole. Offline: always whole.
  virtual bool CheckTool(int flutes) {
    (void)flutes;
    return true;
  }
  // What the machine measured on the tools since the last call (cutting time, for tool life): the run
  // applies it to its table (ToolTable::Charge) before it selects a tool. Offline: nothing.
  virtual std::vector<tooltable::ToolWear> TakeToolWear() { return {}; }
  // Wall clock: year, month, day, hour, minute, second.
  virtual std::array<int, 6> Now();
  // A synchronised block (Balt-System '#', ln 7536-7586) waits here until the machine has finished every move
  // output before it, so that what it reads (the clock, a delay's start) follows the motion. Offline: at
  // once.
  virtual void Synchronize() {}
  // Every file effect of a program, the op as it is output: file_open, file_write, file_close, file_op
  // (copy, delete, print, remote copy, fixture tables). Returns when the machine has done it; offline at
  // once.
  virtual FileResult FileOperation(const Canon& op) {
    (void)op;
    return {};
  }
};

struct RunOptions {
  std::string dialect;       // registry name (cell/interp/interp.h StartRun); unused by Dialect::StartRun
  std::string program_name;  // PROGRAM as given, used in diagnostics
  std::string program_text;
  // Alternative to program_text, shared instead of copied; used when set. ProgramText::MapFile maps a file
  // (long programs: resident memory does not grow with their length).
  std::shared_ptr<const ProgramText> program;
  // Subprograms, subroutines and cycles by name -> text; nullopt when unknown. Offline: files in --lib DIR
  // (NAME, then NAME + each of the dialect's extensions); in the service: the program store.
  std::function<std::optional<std::string>(const std::string& name)> library;
  // Called when a program saves a definition for later programs (KT-APL DFS/DFC with SAVE).
  std::function<void(const std::string& name, const std::string& text)> save;
  // The station's tool table at the start (the run works on its own copy; Run::Tools() returns it).
  tooltable::ToolTable tools;
  // Persistent variables at the start, keyed by the dialect's own names ("L1500", "V1", "E12").
  std::map<std::string, double> variables;
  // Machine settings and initial values ("NAME" -> "VALUE"), per dialect; see docs/dialects/<name>.md.
  std::map<std::string, std::string> params;
  Environment* env = nullptr;  // nullptr: the offline behaviour (immediate answers, no probe contact)
};

struct Step {
  enum Kind { kCanon, kEnd, kError } kind = kEnd;
  Canon canon;
  Diagnostic diag;
};

class Run {
 public:
  virtual ~Run() = default;
  // The next canonical command, or the end of the program, or the (first and last) error.
  // After kEnd or kError every further call returns the same result.
  virtual Step Next() {
    Step s;
    NextInto(s);
    return s;
  }
  // The same, into a Step the caller keeps between calls (long runs: no per-command construction).
  virtual void NextInto(Step& s) = 0;
  // The same without copying the command: the next command where the run keeps it (valid until the next
  // call), or nullptr at the end or the error, which are then in `s`. For callers that only read each
  // command once (the offline CLI's output).
  virtual const Canon* NextInPlace(Step& s) {
    NextInto(s);
    return s.kind == Step::kCanon ? &s.canon : nullptr;
  }
  // Persistent variables as they stand, keyed by the dialect's own names (KT-APL L1000-L2999 as "L1000",
  // Okuma common variables "V1"); the station stores them between runs and gives them to the next.
  virtual std::map<std::string, double> Variables() const = 0;
  // The tool table as the program left it (KT-APL TLD / ZTB, a lathe's offset writes).
  virtual tooltable::ToolTable Tools() const = 0;
};

}  // namespace cell::interp
