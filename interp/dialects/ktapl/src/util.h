// Internal helpers of the KT-APL dialect.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "cell/interp/inline_vec.h"
// Upper, Trim, TrimView, SplitTopLevel, Statement, FindStatements (shared with the heading reader).
#include "cell/interp/ktapl_statements.h"

namespace cell::interp::ktapl {

using ::cell::interp::InlineVec;

}  // namespace cell::interp::ktapl
