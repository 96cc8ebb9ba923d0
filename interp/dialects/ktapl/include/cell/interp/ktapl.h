// Kearney & Trecker KT-APL (KT-GEMINI-D horizontal machining centres in an FMS): the dialect and the helpers
// tests and tools use directly. Everything else goes through the registry (cell/interp/interp.h).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "cell/interp/dialect.h"

namespace cell::interp {

const Dialect& KtaplDialect();

// The program heading (%, NAM, UTL, UCY; manual "Proper Sequence of KT/FMS Program Heading"): NAM, UTL and
// UCY wherever they stand (outside ! comments and other statements' quoted text), every departure from the
// heading rules a notice. One reader for the interpreter, the program store and the scheduler (through
// Dialect::ReadHeading); never throws.
Heading ReadKtaplHeading(std::string_view text, const HeadingOptions& options = {});

// The control's 8-significant-digit number format (FWR, <Ln> file names, parameter display):
// 9.8000000, 123.45670, -45.670000, .25000000, 0.0.
std::string FormatKtNumber(double v);

// The KT-APL source of a shipped library definition (G81-G89), or nullopt.
std::optional<std::string> KtaplStandardLibrary(const std::string& name);

}  // namespace cell::interp
