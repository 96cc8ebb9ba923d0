// Okuma OSP-E100L (lathes, with schedule programs and variables).
#pragma once

#include "cell/interp/dialect.h"

namespace cell::interp {

const Dialect& OkumaDialect();

}  // namespace cell::interp
