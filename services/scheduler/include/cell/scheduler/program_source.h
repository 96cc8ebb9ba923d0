// Program metadata the scheduler needs (the program's dialect and its heading: KT-APL's UTL tool list and UCY
// cycle seconds) and the interface through which it looks programs up. The service implements ProgramSource
// with the program store.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cell::scheduler {

struct ProgramMeta {
  std::string name;
  std::string dialect;             // the registry name the program store recorded (cell/interp/interp.h)
  std::vector<std::string> tools;  // UTL tool numbers, normalised ("T0012" -> "12"), in order, no duplicates
  std::optional<std::int64_t> ucy_s;  // UCY seconds; absent when the program has no UCY statement
  // Not a program: the pallet's part model (the store's type part_model), which the station hands to its
  // axis servo for probing; no tools, no cycle time (docs/scheduler.md, "Part models").
  bool part_model = false;
  // A fingerprint of the program's text and dialect: predictions are kept with it (estimates.h).
  std::string revision;
};

// The scheduler's view of a program's heading, read by its dialect (Dialect::ReadHeading; for KT-APL DESIGN
// §5:
// `(UTL,t1,t2,...)`, tool numbers of up to 7 digits each optionally prefixed with T; `(UCY,nnnnnnn)`, manual
// seed line 4136). Tool numbers are normalised and de-duplicated; the cycle time must be whole seconds.
// Heading order is not checked here. Throws cell::Error (kInvalidArgument) "NAME:LINE:COL: error: text" for
// a malformed tool list or cycle time, and for a dialect the registry does not know.
ProgramMeta ReadProgramMeta(std::string_view text, std::string_view dialect, std::string_view name);

// Looks a program up by name (in the HOST namespace of the program store). nullopt when no such program
// exists. A program that exists but cannot be read may throw cell::Error.
class ProgramSource {
 public:
  virtual ~ProgramSource() = default;
  virtual std::optional<ProgramMeta> Lookup(std::string_view name) = 0;
};

// A program as the store keeps it: its text, the dialect and the type it recorded ("" = a program).
struct StoredProgram {
  std::string text;
  std::string dialect;
  std::string type;
};

// A ProgramSource over stored programs: `fetch` returns a program (nullopt: no such program) and
// ReadProgramMeta reads its heading.
class TextProgramSource : public ProgramSource {
 public:
  using Fetch = std::function<std::optional<StoredProgram>(std::string_view name)>;
  explicit TextProgramSource(Fetch fetch) : fetch_(std::move(fetch)) {}
  std::optional<ProgramMeta> Lookup(std::string_view name) override;

 private:
  Fetch fetch_;
};

// Program texts held in memory (tests, the benchmark, offline tools).
class MemoryProgramSource : public ProgramSource {
 public:
  void Put(std::string name, std::string text, std::string dialect, std::string type = "") {
    texts_[std::move(name)] = {std::move(text), std::move(dialect), std::move(type)};
  }
  void Remove(const std::string& name) { texts_.erase(name); }
  std::optional<ProgramMeta> Lookup(std::string_view name) override;

 private:
  std::map<std::string, StoredProgram, std::less<>> texts_;
};

}  // namespace cell::scheduler
