// Balt-System NC-110/210 (mills).
#pragma once

#include "cell/interp/dialect.h"

namespace cell::interp {

const Dialect& BaltDialect();

}  // namespace cell::interp
