// Balt-System's memory commands on the program store (manual §3.4-3.5, §6.3, ln 1740-2134, 7783-8043;
// catalogue seed-balt.md §10.2): DIR, COP, REN, DEL, ATT, DIF, INI, SPG and REL as the control's keyboard
// takes them ("COP,P9/MP2,P2/MP3"), run against a station's memories. A memory is a store namespace: MP1 (the
// default when a command names none) is the station's own namespace "BS01", MP0 and MP2..MP6 are "BS01/MPn";
// the cell's HOST namespace is the device /HOST (also /HD and /HDO, the control's hard disk). Refusals are
// cell::Error with the control's message: "[FILMS1 05] FILE NOT FOUND IN BUBBLE OR CMOS: P9/MP2".
// Questions the control asks (FILMS2 02 DO YOU CONFIRM?, FILMS2 05 EXISTS DELETE???) are answered by
// `confirm`: without it the command stops at the question, changes nothing and reports it as a refusal.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cell::program_store {

// What the commands need of the store: the library (ProgramStore) or the bus client implements it.
class MemoryBackend {
 public:
  struct Entry {
    std::string name;
    std::uint64_t size = 0;
    bool is_protected = false;
    bool is_selected = false;
    bool is_hidden = false;
  };
  virtual ~MemoryBackend() = default;
  virtual std::vector<Entry> List(const std::string& node, const std::string& pattern) = 0;
  virtual std::optional<std::string> Get(const std::string& node, const std::string& name) = 0;
  virtual void Copy(const std::string& from_node, const std::string& from, const std::string& to_node,
                    const std::string& to, bool force) = 0;
  virtual void Rename(const std::string& node, const std::string& from, const std::string& to) = 0;
  virtual void Delete(const std::string& node, const std::string& name) = 0;
  // flag: "protected", "selected" or "hidden".
  virtual void Flag(const std::string& node, const std::string& name, const std::string& flag, bool on) = 0;
};

// The backend on the store library itself (tests, tools on the store's host).
class ProgramStore;
class StoreMemory : public MemoryBackend {
 public:
  explicit StoreMemory(ProgramStore& store) : store_(store) {}
  std::vector<Entry> List(const std::string& node, const std::string& pattern) override;
  std::optional<std::string> Get(const std::string& node, const std::string& name) override;
  void Copy(const std::string& from_node, const std::string& from, const std::string& to_node,
            const std::string& to, bool force) override;
  void Rename(const std::string& node, const std::string& from, const std::string& to) override;
  void Delete(const std::string& node, const std::string& name) override;
  void Flag(const std::string& node, const std::string& name, const std::string& flag, bool on) override;

 private:
  ProgramStore& store_;
};

struct MemoryCommandResult {
  std::vector<std::string> lines;  // what the control shows (a directory, a displayed file, differences)
  std::string message;             // "[FILMS2 03] COMMAND EXECUTED", "[FILMS2 06] FILE DISPLAYED", ...
  bool differ = false;             // DIF found a difference
};

// The namespace of memory `memory` ("MP0".."MP6", "HOST", "HD", "HDO"; "" = MP1) of `station`. Other
// devices (PR, CT, PP, LP, TY, FD, ...) are not on the cell: FILMS1 04 PERIPHERAL ERROR.
std::string MemoryNamespace(std::string_view station, std::string_view memory);
// A program name in a memory: 1-6 letters and digits, the first a letter, capitals (ln 1981, 8014).
bool IsMemoryProgramName(std::string_view name);

MemoryCommandResult RunMemoryCommand(MemoryBackend& store, std::string_view station, std::string_view command,
                                     bool confirm = false);

}  // namespace cell::program_store
