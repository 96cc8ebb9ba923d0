// The bus's replacement of Fast DDS 2.9's lease check (docs/architecture.md, "The bus's lease check").
#pragma once

namespace cell::bus {

// True when the lease check Fast DDS calls is the bus's own (fastdds_lease_check.cpp): the dynamic linker
// resolved the library's call to this process's definition. False with a Fast DDS other than 2.9, or when
// the executable does not export the symbol, and then the 2.9.1 abort and deadlock are back.
bool FastDdsLeaseCheckMended();

}  // namespace cell::bus
