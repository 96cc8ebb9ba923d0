// A controller language: everything the cell needs to know about one dialect, behind one interface. Each
// dialect implements it in its own library under interp/dialects/<name>/, and the registry
// (cell/interp/interp.h, interp/registry) lists them in one table that the program store, the
// scheduler, cell-interp, the station service and the station config use. The core includes no dialect.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cell/interp/run.h"
#include "cell/tooltable/tooltable.h"

namespace cell::interp {

// What a stored file is (the program store's "type").
enum class FileKind {
  kPartProgram,     // a main program a station runs
  kLibrary,         // subroutines / cycles / subprograms
  kSchedule,        // a schedule program (Okuma .SDF)
  kToolTable,       // tool data in the dialect's own form
  kFixtureOffsets,  // a saved fixture offset table (KT-APL NAME;FXT)
  kInspection,      // an inspection file a program wrote
  kData,            // any other text file
  kPartModel,       // a workpiece for probing (common/partmodel's toml form), named in a pallet map
};

// The machine a dialect programs: the axis servo's station kinds ([machine] kind in a station file). A mill
// (Balt-System) runs on the machining-centre kind.
enum class MachineKind { kMachiningCentre, kLathe };

// One piece of content evidence for dialect detection: what was seen and where.
struct Evidence {
  int line = 0;         // 1-based
  std::string what;     // e.g. "(UTL,...) statement"
  bool strong = false;  // decisive on its own
};

// A departure from the dialect's heading rules, found while reading the heading.
struct HeadingNotice {
  enum class Kind {
    kOrder,  // where a statement stands; its value is still read
    kValue,  // what a statement says is malformed; that part is left out
  };
  Kind kind = Kind::kOrder;
  std::string key;  // the statement it concerns ("NAM", "UTL", "UCY", "O"); "" for the heading as a whole
  int line = 0;     // 1-based; 0 for the program as a whole
  int column = 0;   // 1-based; 0 with line 0
  std::string text;
  // "line N: text" ("text" alone for line 0).
  std::string Format() const;
};

// What the host needs from a program without running it.
struct Heading {
  std::optional<std::string> name;  // the name the program gives itself (KT-APL NAM)
  std::vector<std::string> tools;   // tools it needs (KT-APL UTL), as written
  std::optional<double> cycle_s;    // its expected cycle time (KT-APL UCY)
  std::vector<std::string>
      program_names;  // programs inside the file (Okuma O names, EMCO O numbers, Balt %:NAME)
  std::vector<HeadingNotice> notices;
};

// Collects the program names of a file in order; a name seen again is a kValue notice (selection by name
// would be ambiguous). Returns false for a repeated name.
class ProgramNameCollector {
 public:
  explicit ProgramNameCollector(Heading& h) : h_(h) {}
  bool Add(const std::string& name, int line, std::string_view key);

 private:
  Heading& h_;
  std::map<std::string, int> first_line_;
};

struct HeadingOptions {
  bool part_program = false;   // read as a part program (KT/FMS: a UTL without UCY is a notice)
  bool whole_seconds = false;  // a cycle time with a decimal point is a kValue notice (the scheduler's rule)
};

class Dialect {
 public:
  virtual ~Dialect() = default;

  // Identity.
  virtual std::string_view name() const = 0;   // the registry key and wire name, e.g. "ktapl"
  virtual std::string_view title() const = 0;  // "Kearney & Trecker KT-APL"
  // Other accepted spellings, upper case ("KT-APL", "KT"); the name itself is always accepted.
  virtual std::vector<std::string_view> aliases() const { return {}; }
  virtual MachineKind machine() const = 0;
  // False while a dialect's executor is not built yet: StartRun throws kUnimplemented (cell-interp exit 2);
  // names, detection and headings work already.
  virtual bool implemented() const { return true; }

  // Files. The kinds of file the dialect has (every dialect: part programs; KT-APL: fixture offset tables,
  // Okuma: schedule programs, ...): a file declared of a kind only one dialect has belongs to that dialect.
  virtual std::vector<FileKind> kinds() const = 0;
  // Extensions tried after a bare NAME when a program calls another (offline --lib, the store).
  virtual std::vector<std::string_view> extensions() const = 0;
  // The kind a name implies by its extension, if any (Okuma ".SDF" is a schedule).
  virtual std::optional<FileKind> KindFromName(std::string_view name) const {
    (void)name;
    return std::nullopt;
  }
  // Throws cell::Error(kInvalidArgument) with a one-line reason unless `name` is legal for a file of `kind`.
  virtual void CheckName(std::string_view name, FileKind kind) const = 0;
  // The kind of a file from its content (part program, library, schedule, tool table).
  virtual FileKind Classify(std::string_view text) const = 0;
  // Appends what in `text` is distinctive of this dialect (the store scores all dialects' evidence).
  virtual void FindEvidence(std::string_view text, std::vector<Evidence>& out) const = 0;
  // Heading data: never throws; departures from the rules are notices.
  virtual Heading ReadHeading(std::string_view text, const HeadingOptions& options) const = 0;

  // Runs.
  virtual std::unique_ptr<Run> StartRun(const RunOptions& options) const = 0;
  // A tool table written in the dialect's own form, applied on top of `base` (a load changes the entries
  // it names). Throws cell::Error(kInvalidArgument) "SOURCE:LINE:COL: error: text" at the first bad entry,
  // or when the text holds no tool data at all.
  virtual tooltable::ToolTable ParseToolTable(std::string_view text, std::string_view source,
                                              const tooltable::ToolTable& base) const = 0;
  // One tool data set that did not come through ParseToolTable (a station file's [[tools]]) against the
  // same ranges and formats the dialect's tool-table form enforces: "" when it fits, else a one-line
  // reason in the manual's terms. The default asks only for finite numbers.
  virtual std::string CheckToolEntry(const tooltable::ToolEntry& entry) const;
  // The manual's printed listing style turned into the tape format (EMCO --listing); others throw
  // cell::Error(kInvalidArgument).
  virtual std::string ImportListing(std::string_view text) const;

  // The variables a station of this dialect keeps between runs (what Run::Variables() reports, by the
  // dialect's own names: KT-APL machine parameters "L1000".."L2999"; Okuma common variables, Balt-System
  // E parameters when those dialects run). "" when `name` is one of them and `value` fits it; otherwise a
  // one-line reason (the station refuses `cellctl station vars --set` with it). The default keeps none.
  virtual std::string CheckVariable(std::string_view name, double value) const;
  // A pallet arrives with the tool put away and the spindle and coolant stopped (the servo's
  // Machine::ToArrival, docs/predict.md judgement call 4). A dialect whose kept variables carry that state
  // into the next program (CheckVariable's) sets them so for a pallet's first program; the default keeps
  // none.
  virtual void PalletArrives(std::map<std::string, double>& variables) const;
};

// A dialect whose executor is not built yet: identity, names, detection and headings of its own, and
// StartRun / ParseToolTable refused with kUnimplemented.
class UnimplementedRuns : public Dialect {
 public:
  bool implemented() const override { return false; }
  std::unique_ptr<Run> StartRun(const RunOptions& options) const override;
  tooltable::ToolTable ParseToolTable(std::string_view text, std::string_view source,
                                      const tooltable::ToolTable& base) const override;
};

std::string_view FileKindName(FileKind kind);        // "part_program", "library", ...
std::string_view MachineKindName(MachineKind kind);  // "hmc", "lathe"

}  // namespace cell::interp
