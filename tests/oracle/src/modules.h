// The dialect modules (one file each) the registry in modules.cpp lists.
#pragma once

#include "cell/oracle/oracle.h"

namespace cell::oracle {

const Module& BaltModule();
const Module& KtaplModule();
const Module& EmcoModule();
const Module& OkumaModule();

}  // namespace cell::oracle
