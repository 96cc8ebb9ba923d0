// Which DDS stack a process uses and which participant profile it loads (DESIGN.md §3, docs/operations.md
// "Mixing vendors" and "Running across hosts"). Every function reads the environment at call time.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace cell::config {

// The DDS stacks a process can run on (CELL_DDS, a station file's `dds`).
inline constexpr std::string_view kDdsVendors[] = {"fastdds", "cyclonedds"};
bool IsDdsVendor(std::string_view v);
std::string DdsVendorList();  // "fastdds, cyclonedds"

struct DdsChoice {
  std::string vendor;  // one of kDdsVendors
  std::string source;  // where it came from, for the log: "the station file", "CELL_DDS", "the default"
};

// The DDS stack of this process: `station_setting` when not empty (the `dds` of a station's file: the
// stack of that machine's control, for the station's interpreter and servo); else CELL_DDS (the process's
// environment: cell.env, a unit's drop-in, a shell); else fastdds. A station file is the more specific
// setting, so it wins over a cell-wide CELL_DDS. Throws cell::Error(kInvalidArgument) naming the setting and
// the allowed values (a bad CELL_DDS is an error even when the station file decides).
DdsChoice DdsVendor(std::string_view station_setting = {});

// The participant profile file for `vendor`, from CELL_DDS_PROFILE:
//   unset or empty         -> empty path: the built-in loopback-only profile;
//   a path (has a '/')     -> that file, whatever the vendor (one process, one stack);
//   a name such as "lan"   -> <ConfigDir()>/dds/<name>.<vendor>.xml, so that one setting serves both stacks
//                             of a mixed cell (deploy/dds/lan.fastdds.xml, deploy/dds/lan.cyclonedds.xml).
// Throws cell::Error: kInvalidArgument for a malformed name, kNotFound when the file does not exist.
std::filesystem::path DdsProfile(std::string_view vendor);

// A profile's text with ${NAME} and ${NAME:-default} replaced from the environment (the default is
// expanded too), so one shipped file serves every host of a cell (CELL_LAN_ADDRESS, CELL_LAN_PEER). `$$` is
// a literal '$'. Throws cell::Error(kInvalidArgument) naming `what` and the variable when one is unset and
// has no default, or a reference is not closed.
std::string ExpandEnvironment(std::string_view text, std::string_view what);

// How many participants one host's discovery is sized for (DESIGN.md §3, docs/operations.md "A cell's size"):
// the unicast ports every participant probes on loopback (Fast DDS maxInitialPeersRange, Cyclone
// MaxAutoParticipantIndex) and the participant slots a process may take. CELL_DDS_PARTICIPANTS (8..kMaxDds-
// Participants) when set; else two per configured station (interpreter and servo) plus 16 (host services,
// the dashboard, cellctl and tools), at least 32, rounded up to a multiple of 8, at most kMaxDdsParticipants
// less kClientSlots. Every process of a cell reads the same configuration, so every one probes the same
// ports. Throws cell::Error(kInvalidArgument) for a malformed CELL_DDS_PARTICIPANTS.
inline constexpr int kMaxDdsParticipants = 120;  // (250 ports per domain - 10) / 2 ports per participant
// Slots above the largest computed range, which no participant announces itself to: a client of the host
// services only takes one of these, so only the services it calls ever hear of it (on Fast DDS 2.9 each
// participant that discovers a newcomer heartbeats every peer it knows once for each endpoint it sends the
// newcomer: the dashboard of a 64-station cell did so for every `cellctl job ls`; docs/operations.md §9.4).
inline constexpr int kClientSlots = 8;
int DdsParticipants();

// Reads a profile file and expands it (above). Throws cell::Error(kIo) when it cannot be read.
std::string LoadDdsProfile(const std::filesystem::path& file);

}  // namespace cell::config
