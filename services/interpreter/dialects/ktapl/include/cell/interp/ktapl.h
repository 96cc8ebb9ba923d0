// KT-APL (Kearney & Trecker KT-GEMINI-D) dialect: helpers reusable outside a run.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cell/interp/interp.h"
// KtaplMetadata, ExtractKtaplMetadata: the program heading (%, NAM, UTL, UCY) for the interpreter, the
// program store and the scheduler (DESIGN §5), in the small library cell_ktapl_meta.
#include "cell/interp/ktapl_meta.h"

namespace cell::interp {

// The control's 8-significant-digit number format (FWR, <Ln> file names, parameter display):
// 9.8000000, 123.45670, -45.670000, .25000000, 0.0.
std::string FormatKtNumber(double v);

// Reads a tool table written as a KT-APL program of (TLD,...) statements (G70/G71 blocks set the unit).
// Throws cell::Error(kInvalidArgument) with "LINE: text" on a malformed statement.
std::vector<ToolEntry> ParseKtaplToolTable(std::string_view text);

// The KT-APL source of a shipped library definition (G81-G89), or nullopt.
std::optional<std::string> KtaplStandardLibrary(const std::string& name);

// Starts a KT-APL run (what StartRun does for dialect "ktapl").
std::unique_ptr<Run> StartKtaplRun(const RunOptions& options);

}  // namespace cell::interp
