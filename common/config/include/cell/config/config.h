// Where the cell's configuration and state live, which DDS domain it uses, and the station configs
// (DESIGN.md §7). Every function reads the environment at call time; nothing is cached.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cell/tooltable/tooltable.h"

namespace cell::config {

// CELL_CONFIG_DIR if set; else /etc/cell when the running binary is installed (its path is under /usr or
// /opt); else the source tree's deploy/ directory (the tree this library was built from).
std::filesystem::path ConfigDir();

// The rule above without the environment variable, for a binary at `exe` (exposed for tests).
std::filesystem::path DefaultConfigDir(const std::filesystem::path& exe);

// The source tree this library was built from (its deploy/ holds the shipped units and stations; `cellctl
// up` reads <SourceTreeDir()>/deploy/systemd).
std::filesystem::path SourceTreeDir();

// CELL_DATA_DIR if set; else $XDG_STATE_HOME/cell (XDG_STATE_HOME must be absolute); else
// $HOME/.local/state/cell (the passwd home when HOME is unset). Creates the directory (and parents).
// Throws cell::Error(kIo) naming the directory when it cannot be created.
std::filesystem::path DataDir();

// CELL_DOMAIN (decimal, 0..232), default 101. Throws cell::Error(kInvalidArgument) with a message naming
// the variable, the value and the allowed range.
int Domain();
inline constexpr int kDefaultDomain = 101;
inline constexpr int kMaxDomain = 232;

// CELL_SECURITY: "on" or "off" (unset or empty: off). On, every participant of the process joins with DDS
// Security under its identity (docs/security.md). Throws cell::Error(kInvalidArgument) naming the variable
// and the value for anything else.
bool SecurityOn();
// CELL_IDENTITY: the security identity the process claims instead of its default (cellctl's is "operator";
// "viewer" for read-only); empty when unset.
std::string IdentityOverride();

// A station file `<ConfigDir()>/stations/<ID>.toml`:
//
//   [station]
//   id = "KT01"              # must equal the file name's stem
//   dialect = "ktapl"        # a dialect of the registry (DialectRules below): ktapl | okuma | emco | balt
//   description = "..."      # optional, default ""
//   coded_pallets = false    # optional, default false (KT-APL coded-pallet FMS module: pallets 1-127)
//   dds = "cyclonedds"       # optional: the DDS stack of the station's processes (wins over CELL_DDS)
//
//   [[tools]]                # optional, any number: the initial tool table (common/tooltable's ToolEntry)
//   tool = "1001"            # string (or integer); suffix tools as strings: "33412.5"
//   socket = 1               # magazine socket / turret station, 1..9999
//   length = 152.4           # mm, signed (optional, default 0); length_axis = "Z" for a mill's other axes
//   diameter = 25.0          # mm, signed (optional)
//   life_left_min = 120      # minutes, >= 0 (optional)
//   x_offset, z_offset       # lathes: mm, signed (optional)
//   nose_radius, tip         # lathes: mm >= 0, tip position code 0..9 (optional)
//
//   [params]                 # optional: the dialect's machine settings, given to every run as
//   O11 = 9                  # interp::RunOptions::params (EMCO's operator monitor, docs/dialects/emco.md);
//   S01 = 2                  # values are strings, numbers or booleans (1/0); names 1-32 of A-Z a-z 0-9 _ . -
//
//   [[io.aux]]               # optional, any number: a device the M codes drive through one discrete output
//   name = "chuck"           # what it is, in messages (1-32 characters)
//   output = "CHUCK"         # the output it drives (IsValidIoName); `cellctl station io` shows it
//   m_on = 83                # M code setting the output to 1 (optional; 0..999)
//   m_off = 84               # M code setting it to 0 (optional; at least one of m_on and m_off)
//   interlock = true         # optional, default false: m_on / m_off are refused while the spindle rotates
//   interlock_on = 184       # optional (needs interlock): M codes switching that interlock ON and OFF; it is
//   interlock_off = 185      #   ON again at every program start (the control's reset state)
//   note = "OSP-E100L ln 2015-2023"  # optional (up to 80 characters): the source, quoted in the refusal
//
//   [serial]                 # optional: the station's DNC line (DESIGN §6b, docs/dnc.md); with it
//   device = "/dev/ttyS0"    # `cellctl up` and systemd run cell-dnc@ID. device is required (an absolute
//   baud = 9600              # path); every other key defaults to the control's manual and is checked
//   data_bits = 7            # against it by cell-dnc (cell::dnc::Resolve): data_bits, stop_bits, leader
//   parity = "even"          # integers; parity none|even|odd, code eia|iso, flow xonxoff|rtscts|none,
//   stop_bits = 1            # end nul|ctrl-z|%
//   code = "iso"
//   flow = "xonxoff"
//   end = "nul"
//   leader = 50              # NUL characters before and after a program
//
// With DialectRules, each [[tools]] entry must also fit the station dialect's own ranges (check_tool;
// KT-APL: the TLD statement's, socket 1-999, length and diameter +-999.999 mm, life up to 99 h 59 min).
// Unknown keys inside [station], [[tools]] and [[io.aux]] are errors (typos must not pass silently); other
// tables ([machine], [axes.x], [magazine], ...) belong to other readers and are ignored here.

// One [[io.aux]] entry; an absent M code is -1.
struct AuxOutput {
  std::string name;
  std::string output;
  int m_on = -1;
  int m_off = -1;
  bool interlock = false;
  int interlock_on = -1;
  int interlock_off = -1;
  std::string note;
  bool operator==(const AuxOutput&) const = default;
};

// A [serial] table as written: an absent key is nullopt (its default is the control's, cell::dnc).
struct SerialTable {
  std::string device;
  std::optional<int> baud, data_bits, stop_bits, leader;
  std::optional<int>
      memory;  // characters the control's memory takes (0: no limit); cell-dnc's default otherwise
  std::optional<std::string> parity, code, flow, end;
  bool operator==(const SerialTable&) const = default;
};

struct StationConfig {
  std::string id;
  std::string dialect;
  std::string description;
  bool coded_pallets = false;
  std::string dds;  // "", "fastdds" or "cyclonedds" (cell/config/dds.h: DdsVendor)
  std::vector<tooltable::ToolEntry> tools;
  std::map<std::string, std::string> params;  // [params]
  std::vector<AuxOutput> aux;                 // [[io.aux]]
  std::optional<SerialTable> serial;          // [serial]
  std::filesystem::path file;                 // the file it was read from
};

// What a station file's dialect is checked against. The interpreter's registry supplies them
// (cell/interp/station_rules.h, the tier above): this library names dialects as strings and links none, and
// the processes that run programs consult the registry. Without rules a dialect is any name of 1-32 letters,
// digits,
// '_' or '-', kept as written, and tools are checked only for what every dialect shares.
struct DialectRules {
  std::string names;  // every dialect's name, for messages: "ktapl, okuma, emco, balt"
  // The dialect's own name for `name` (an alias, any case), or "" when no dialect has it.
  std::function<std::string(std::string_view name)> canonical;
  // Why `tool` does not fit the ranges of `dialect` (a name canonical returned), or "".
  std::function<std::string(std::string_view dialect, const tooltable::ToolEntry& tool)> check_tool;
};

// Station ids (file stems of <ConfigDir()>/stations/*.toml), sorted. Throws cell::Error(kNotFound) when
// the stations directory does not exist.
std::vector<std::string> ListStations();

// Reads and validates <ConfigDir()>/stations/<id>.toml. Throws cell::Error: kInvalidArgument for a
// malformed id or file (the message names the file, line, key and allowed values), kNotFound when there
// is no such station (the message lists the configured ones).
StationConfig LoadStation(std::string_view id, const DialectRules* rules = nullptr);

// Same for an explicit file; the [station] id must equal the file's stem.
StationConfig LoadStationFile(const std::filesystem::path& file, const DialectRules* rules = nullptr);

// True for a well-formed station id: 1-16 characters of A-Z, a-z, 0-9, '_' or '-'.
bool IsValidStationId(std::string_view id);

// True for a well-formed discrete input or output name: 1-16 characters of A-Z, 0-9, '_', '.', '[' or
// ']', starting with a letter ("O83D.0", "I04D.1", "VDOUT[5]", "CHUCK").
bool IsValidIoName(std::string_view name);

// True for a well-formed tool number: 1-7 digits, optionally ".1" to ".7".
bool IsValidToolNumber(std::string_view tool);

}  // namespace cell::config
