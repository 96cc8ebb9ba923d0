// EMCOTRONIC TM02 (lathes).
#pragma once

#include "cell/interp/dialect.h"

namespace cell::interp {

const Dialect& EmcoDialect();

}  // namespace cell::interp
