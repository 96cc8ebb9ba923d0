// The interpreter's front door: start a run of a part program and pull canonical commands from it.
//
//   cell::interp::RunOptions opt;
//   opt.dialect = "ktapl";
//   opt.program_name = "PUMP341";
//   opt.program_text = text;
//   auto run = cell::interp::StartRun(opt);          // throws cell::Error(kUnimplemented) for unknown
//   dialects for (;;) {
//     cell::interp::Step s = run->Next();            // blocks only inside Environment callbacks
//     if (s.kind == cell::interp::Step::kCanon) publish(s.canon);
//     else if (s.kind == cell::interp::Step::kEnd) break;   // ran to its end
//     else { report(s.diag); break; }                 // kError: the run stops at the first error
//   }
//
// Memory does not grow with program length: the program text is scanned block by block, and a mapped
// program (ProgramText::MapFile) gives back the pages the run has passed.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cell/interp/canon.h"
#include "cell/interp/program_text.h"

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

// One entry of the station's tool table (KT-APL TLD data). Lengths are millimetres.
struct ToolEntry {
  std::string tool;  // "33412" or "33412.5" (suffix set)
  int socket = 0;
  double length = 0;    // P: length compensation
  double diameter = 0;  // D: diameter compensation
  int pallet = 0;       // W: process compensation for this pallet (0 = primary / suffix data)
  int life_min = 0;     // L (hhmm) converted to minutes
  double max_hp = 0;    // H
  bool check = false, manual = false, broken = false, worn = false;
};

// Result of a probe move (G22 contact / G23 break).
struct ProbeResult {
  bool already = false;                 // already in the requested state at the start: no motion
  bool event = false;                   // the contact (break) happened
  std::array<double, kAxisCount> at{};  // machine position where the event happened (mm / deg)
};

// Queue busters: everything whose result the program reads. The offline CLI answers at once; the service
// answers over DDS (a blocking call is fine).
class Environment {
 public:
  virtual ~Environment() = default;
  // A G22 (contact=true) or G23 move from `from` to `to` (machine coordinates).
  virtual ProbeResult Probe(bool contact, const std::array<double, kAxisCount>& from,
                            const std::array<double, kAxisCount>& to);
  // (WAI,...): returns when the inputs match. Offline: at once.
  virtual void WaitInputs(const std::string& spec) { (void)spec; }
  // Machine state fed into the read-only system parameters (L3000-L3999); nullopt = not known (0).
  virtual std::optional<double> SystemParameter(int number) {
    (void)number;
    return std::nullopt;
  }
  // Wall clock for (DAT): year, month, day, hour, minute, second.
  virtual std::array<int, 6> Now();
  // Completion of file operations (CLF, DLF, PRT, CPY, RCP): true = finished.
  virtual bool FileOperation(const Canon& op) {
    (void)op;
    return true;
  }
};

struct RunOptions {
  std::string dialect = "ktapl";  // ktapl, okuma, emco, balt
  std::string program_name;       // PROGRAM as given, used in diagnostics
  std::string program_text;
  // Alternative to program_text, shared instead of copied; used when set. ProgramText::MapFile maps a file
  // (long programs: resident memory does not grow with their length).
  std::shared_ptr<const ProgramText> program;
  // SAVE-d subroutines and cycles (and, for KT-APL, user overrides of the shipped G81-G89): name -> text.
  // Offline: files in --lib DIR; in the service: the program store. Return nullopt when unknown.
  std::function<std::optional<std::string>(const std::string& name)> library;
  // Called for (DFS,name,SAVE) / (DFC,Gnnn,SAVE) with the definition text; may be empty.
  std::function<void(const std::string& name, const std::string& text)> save;
  std::vector<ToolEntry> tools;
  // Initial parameters ("L1000" -> 5.0) and machine settings; see docs/dialects/ktapl.md
  // (UNITS=inch|mm, BLOCK_DELETE=0|1, OPTIONAL_STOP=0|1, PALLET=n, B_AXIS=index|rotary).
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
  virtual Step Next() = 0;
  // The same, into a Step the caller keeps between calls (long runs: no per-command construction).
  virtual void NextInto(Step& s) { s = Next(); }
  // Persistent machine parameters (L1000-L2999) as they stand; the service stores them between runs.
  virtual std::map<int, double> MachineParameters() const = 0;
  // The tool table as modified by TLD / ZTB.
  virtual std::vector<ToolEntry> Tools() const = 0;
};

// Dialect registry.
struct DialectInfo {
  std::string name;
  bool implemented = false;
};
const std::vector<DialectInfo>& Dialects();
// nullptr when the name is not a dialect at all.
const DialectInfo* FindDialect(const std::string& name);

// Throws cell::Error(kInvalidArgument) for an unknown dialect and cell::Error(kUnimplemented) for a
// dialect that is not implemented yet.
std::unique_ptr<Run> StartRun(const RunOptions& options);

}  // namespace cell::interp
