// Program metadata the scheduler needs (KT-APL FMS heading: UTL tool list, UCY cycle seconds) and the
// interface through which it looks programs up. The service implements ProgramSource with the program store.
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
  std::vector<std::string> tools;  // UTL tool numbers, normalised ("T0012" -> "12"), in order, no duplicates
  std::optional<std::int64_t> ucy_s;  // UCY seconds; absent when the program has no UCY statement
};

// The scheduler's view of a KT-APL program's heading, read by cell::interp::ExtractKtaplMetadata (DESIGN §5:
// `(UTL,t1,t2,...)`, tool numbers of up to 7 digits each optionally prefixed with T; `(UCY,nnnnnnn)`, manual
// seed line 4136). Tool numbers are normalised and de-duplicated; UCY must be whole seconds. Heading order is
// not checked here. Throws cell::Error (kInvalidArgument) "NAME:LINE:COL: error: text" for a malformed UTL or
// UCY (a bad tool entry, a bad or second UCY, a missing ',' or closing character).
ProgramMeta KtaplProgramMeta(std::string_view text, std::string_view name);

// Looks a program up by name (in the HOST namespace of the program store). nullopt when no such program
// exists. A program that exists but cannot be read may throw cell::Error.
class ProgramSource {
 public:
  virtual ~ProgramSource() = default;
  virtual std::optional<ProgramMeta> Lookup(std::string_view name) = 0;
};

// A ProgramSource over program text: `fetch` returns the text of a program (nullopt: no such program) and
// KtaplProgramMeta reads UTL/UCY from it.
class TextProgramSource : public ProgramSource {
 public:
  using Fetch = std::function<std::optional<std::string>(std::string_view name)>;
  explicit TextProgramSource(Fetch fetch) : fetch_(std::move(fetch)) {}
  std::optional<ProgramMeta> Lookup(std::string_view name) override;

 private:
  Fetch fetch_;
};

// Program texts held in memory (tests, the benchmark, offline tools).
class MemoryProgramSource : public ProgramSource {
 public:
  void Put(std::string name, std::string text) { texts_[std::move(name)] = std::move(text); }
  void Remove(const std::string& name) { texts_.erase(name); }
  std::optional<ProgramMeta> Lookup(std::string_view name) override;

 private:
  std::map<std::string, std::string, std::less<>> texts_;
};

}  // namespace cell::scheduler
