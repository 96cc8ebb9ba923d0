// Okuma OSP schedule programs (.SDF), DESIGN §5 and the OSP-E100L manual SECTION 14 (seed
// /work/shared/seeds/okuma-osp-e100l.txt lines 8767-8962).
//
// A schedule program is made of five block types only (seed 8774-8784); any other block is an alarm:
//   [Nxxxx ]PSELECT [fm],[pm],[fs],[Q=n]   run main program pm of file fm (subprograms from fs) n times,
//   1-9999 [Nxxxx ]GOTO Nxxxx                     unconditional branch [Nxxxx ]IF [expr op expr] Nxxxx
//   conditional branch, op one of LT LE EQ NE GE GT [Nxxxx ]VSET var=expr [var=expr ...]   set common
//   variables V1-V200 [Nxxxx ]END                            end of the schedule; everything after it is
//   ignored
// Comments in ( ) and continuation lines starting with '$' are allowed; block delete '/' is not (seed 8785).
// Expressions: numbers, V1-V200, + - * /, unary minus, [ ] grouping.
//
// Alarms (the manual gives no numbers for them, so diagnostics carry none):
//   illegal block type; '*' or '?' in a file name; device > 3, file name > 16, extension > 3 characters;
//   program name not O + up to 4 characters; Q outside 1-9999 (evaluated when the PSELECT runs); VSET of
//   anything but a common variable; an output variable (VDOUT) on the right; a jump to a missing sequence
//   name (when executed); reading a variable that is not V1-V200; division by zero; a missing END.
// Deviation: VSET of system and output variables is refused: they live in the station's CNC, and the cell's
// scheduler sets the station's common variables only (DESIGN §5).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cell::scheduler::schedule {

struct Expr;  // parsed expression (opaque)

struct FileSpec {
  std::string device = "MD1";
  std::string name;
  std::string ext;
  std::string Full() const { return device + ":" + name + "." + ext; }  // "MD1:A.MIN"
};

struct Block {
  enum class Kind { kPselect, kGoto, kIf, kVset, kEnd };
  Kind kind = Kind::kEnd;
  int line = 0;     // 1-based source line of the block
  std::string seq;  // sequence name ("N010"), empty if none
  // PSELECT
  FileSpec main_file;
  std::string program;  // "O100"; empty: the first program of the file
  std::optional<FileSpec> sub_file;
  std::shared_ptr<const Expr> count;  // Q; null = 1
  // GOTO / IF
  std::string target;
  std::shared_ptr<const Expr> lhs, rhs;
  std::string op;  // LT LE EQ NE GE GT
  // VSET
  std::vector<std::pair<int, std::shared_ptr<const Expr>>> sets;  // V number, value
};

struct Program {
  std::string name;
  std::vector<Block> blocks;  // up to and including END
};

// Parses a schedule program. Throws cell::Error (kInvalidArgument) "NAME:LINE:COL: error: text".
Program Parse(std::string_view text, std::string_view name);

// The station's common variables V1-V200 (they live on the station and persist there).
class Variables {
 public:
  virtual ~Variables() = default;
  virtual double Get(int n) = 0;
  virtual void Set(int n, double value) = 0;
};

// One run of a main program requested by a PSELECT.
struct Run {
  std::string main_file;  // "MD1:A.MIN"
  std::string program;    // "O100" or "" (first program of the file)
  std::string sub_file;   // "MD1:S.SUB" or ""
  int index = 1;          // 1..count
  int count = 1;
  int line = 0;
};

// The run as the station receives it (the dispatch's one program entry): PSELECT's own operands without the
// device, "A.MIN,O100,S.SUB"; "A.MIN" alone when neither a program nor a subprogram file was given. The
// station runs program O100 of A.MIN and searches S.SUB for subprograms (docs/scheduler.md §9).
std::string StationEntry(const Run& run);

struct Step {
  enum class Kind { kRun, kEnd, kAlarm };
  Kind kind = Kind::kEnd;
  Run run;            // kRun
  std::string alarm;  // kAlarm: "NAME:LINE:COL: error: text"
};

// Steps a schedule: Next() executes GOTO/IF/VSET blocks up to the next main-program run, END or an alarm.
// Call it again after each run has finished. The position is plain data, so a caller can persist it and
// resume.
struct RunnerPosition {
  std::size_t pc = 0;  // block index
  int done = 0;        // runs of the current PSELECT already requested
  int count = 0;       // its repeat count (0: not evaluated yet)
  bool finished = false;
};

class Runner {
 public:
  using Position = RunnerPosition;

  explicit Runner(std::shared_ptr<const Program> program, Position at = Position());
  Step Next(Variables& vars);
  const Position& position() const { return pos_; }

 private:
  std::shared_ptr<const Program> program_;
  Position pos_;
};

}  // namespace cell::scheduler::schedule
