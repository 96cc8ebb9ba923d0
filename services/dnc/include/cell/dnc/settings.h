// A station's serial line (DESIGN §6b `[serial]`): every key but `device` defaults to the control's manual
// (docs/dnc.md "Defaults", each a numbered judgement call).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "cell/config/config.h"
#include "cell/dnc/codes.h"

namespace cell::dnc {

enum class Flow { kXonXoff, kRtsCts, kNone };
std::string_view FlowName(Flow f);  // "xonxoff", "rtscts", "none"

struct Serial {
  std::string device;
  int baud = 9600;
  int stop_bits = 1;
  Flow flow = Flow::kXonXoff;
  Format format;  // code, data bits, parity, end of data, leader/trailer
  // The characters of one program the control's memory takes (docs/dnc.md "Memory"; 0: not known, no
  // check): a send (not a drip) of a longer program is refused before a byte goes out.
  int memory = 0;
};

// The control's defaults (device empty).
Serial Defaults(Control c);

// The control's defaults overlaid with a station file's [serial] table (common/config reads it), checked: the
// baud one termios knows and the control accepts (EMCO 150-4800, alarm 870 ln 7225), 7 or 8 data bits, 1 or 2
// stop bits, EIA with 8 data bits and odd or no parity and no ctrl-Z, leader 0-1000. Throws
// Error(kInvalidArgument) naming the key, the value and what is allowed.
Serial Resolve(Control c, const config::SerialTable& keys);

// Why a program of `characters` (its text, one per end of block) cannot be sent, as opposed to dripped: a
// send fills the control's memory, and a longer program would overflow it part-way after minutes on the
// line. "" when it fits or the memory is not known.
std::string MemoryRefusal(const Serial& s, size_t characters);

}  // namespace cell::dnc
