// The interpreter's front door: the one table of dialects (DESIGN §4) and starting a run by dialect name.
// The program store, the scheduler, cell-interp, the station service and the station config ask this table;
// there is no other list of dialect names in the product. Adding a dialect is a folder under dialects/ and
// one line in registry.cpp.
//
//   const Dialect* d = cell::interp::FindDialect("okuma");   // also aliases: "OSP", "kt-apl", ...
//   auto run = cell::interp::StartRun(opt);                  // opt.dialect names the dialect
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "cell/interp/dialect.h"
#include "cell/interp/run.h"

namespace cell::interp {

// Every dialect, in the registry's order (KT-APL, Okuma, EMCO, Balt-System).
const std::vector<const Dialect*>& Dialects();

// By name or alias, case-insensitive; nullptr when none matches.
const Dialect* FindDialect(std::string_view name);

// Like FindDialect, but throws cell::Error(kInvalidArgument) "unknown dialect 'X' (use ktapl, okuma, emco or
// balt)".
const Dialect& DialectOrThrow(std::string_view name);

// "ktapl, okuma, emco or balt" (for messages) and "ktapl|okuma|emco|balt" (for usage lines).
std::string DialectList();
std::string DialectChoices();

// Starts a run of options.dialect. Throws cell::Error(kInvalidArgument) for an unknown dialect and
// cell::Error(kUnimplemented) for a dialect whose executor is not built yet.
std::unique_ptr<Run> StartRun(const RunOptions& options);

}  // namespace cell::interp
