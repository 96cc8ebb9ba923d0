// KT-APL (Kearney & Trecker KT-GEMINI-D) dialect: helpers reusable outside a run.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cell/interp/interp.h"

namespace cell::interp {

// Program heading data for the program store and the scheduler (DESIGN §5).
struct KtaplMetadata {
  std::optional<std::string> name;    // (NAM,name), trimmed
  std::vector<std::string> tools;     // (UTL,t1,t2,...): tool numbers without the T prefix
  std::optional<long> cycle_s;        // (UCY,seconds)
  std::vector<std::string> warnings;  // placement and format problems, "LINE: text"
};

// Scans the heading (%, NAM, UTL, UCY) of a KT-APL program. Never throws.
KtaplMetadata ExtractKtaplMetadata(std::string_view text);

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
