// Balt-System memory commands on the store (see memory_commands.h).
#include "cell/program_store/memory_commands.h"

#include <algorithm>
#include <cctype>
#include <map>

#include <fmt/format.h>

#include "cell/error/error.h"
#include "cell/program_store/program_store.h"

namespace cell::program_store {

namespace {

// The control's messages (Tables 8.3-8.5, ln 9549-9770).
constexpr const char* kNotFound = "[FILMS1 05] FILE NOT FOUND IN BUBBLE OR CMOS";
constexpr const char* kPeripheral = "[FILMS1 04] PERIPHERAL ERROR";
constexpr const char* kInvalid = "[FILMS1 08] INVALID COMMAND";
constexpr const char* kFormat = "[FILMS1 09] FORMAT ERROR";
constexpr const char* kSyntax = "[FILMS1 10] SYNTAX ERROR";
constexpr const char* kIllegal = "[FILMS1 14] ILLEGAL REQUEST";
constexpr const char* kConfirm = "[FILMS2 02] DO YOU CONFIRM? (Y/N)";
constexpr const char* kExecuted = "[FILMS2 03] COMMAND EXECUTED";
constexpr const char* kExists = "[FILMS2 05] EXISTS DELETE??? (Y/N)";
constexpr const char* kDisplayed = "[FILMS2 06] FILE DISPLAYED";
constexpr const char* kContinue = "[FILMS2 09] DO YOU CONTINUE? (Y/N)";
constexpr const char* kInvalidOperation = "[FILMS3 20] INVALID OPERATION";
constexpr const char* kWriteProtected = "[FILMS3 26] WRITE PROTECTED FILE";

[[noreturn]] void Refuse(Errc code, const char* message, const std::string& detail) {
  throw Error(code, fmt::format("{}: {}", message, detail));
}

std::string_view Trim(std::string_view s) {
  while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
  while (!s.empty() && s.back() == ' ') s.remove_suffix(1);
  return s;
}

// NAME[/DEV] as the command wrote it.
struct Operand {
  std::string name;
  std::string device;  // without the '/'; empty: MP1
  bool has_device = false;
  bool wild() const { return name.empty() || name.find('*') != std::string::npos; }
  std::string Shown() const { return has_device ? name + "/" + device : name; }
};

Operand ParseOperand(std::string_view text, std::string_view command) {
  Operand o;
  const std::size_t slash = text.find('/');
  o.name = std::string(Trim(text.substr(0, slash)));
  if (slash != std::string_view::npos) {
    o.has_device = true;
    o.device = std::string(Trim(text.substr(slash + 1)));
    if (o.device.empty() || o.device.find('/') != std::string::npos)
      Refuse(Errc::kInvalidArgument, kSyntax, std::string(command));
  }
  for (char c : o.name) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '*'))
      Refuse(Errc::kInvalidArgument, kSyntax, std::string(command));
  }
  return o;
}

struct Parsed {
  std::string mnemonic;
  std::vector<std::string> operands;
};

// "COP,P9/MP2,P2/MP3", "COP, P9/MP2, P2/MP3", "COP P9, /MP2" (ln 2068-2080), "DIR/MP3" (ln 1503).
Parsed Parse(std::string_view command) {
  std::string_view c = Trim(command);
  if (c.size() < 3) Refuse(Errc::kInvalidArgument, kInvalid, std::string(command));
  Parsed p;
  p.mnemonic = std::string(c.substr(0, 3));
  std::string_view rest = c.substr(3);
  if (!rest.empty() && rest.front() != ',' && rest.front() != ' ' && rest.front() != '/')
    Refuse(Errc::kInvalidArgument, kInvalid, std::string(command));
  rest = Trim(rest);
  if (!rest.empty() && rest.front() == ',') rest = Trim(rest.substr(1));
  while (!rest.empty()) {
    const std::size_t comma = rest.find(',');
    p.operands.emplace_back(Trim(rest.substr(0, comma)));
    if (comma == std::string_view::npos) break;
    rest = rest.substr(comma + 1);
    if (Trim(rest).empty()) p.operands.emplace_back();
  }
  return p;
}

// Every memory of a station: MP1 (the station's namespace), MP0, MP2..MP6.
std::vector<std::string> StationMemories(std::string_view station) {
  std::vector<std::string> out = {std::string(station)};
  for (const char* mp : {"MP0", "MP2", "MP3", "MP4", "MP5", "MP6"})
    out.push_back(MemoryNamespace(station, mp));
  return out;
}

bool IsHost(const std::string& node) {
  return node == kHostNamespace;
}

void CheckNewName(const std::string& node, const std::string& name, std::string_view command) {
  if (!IsHost(node) && !IsMemoryProgramName(name)) {
    Refuse(Errc::kInvalidArgument, kFormat,
           fmt::format("{}: '{}' is not a program name (1-6 capitals and digits, the first a letter)",
                       command, name));
  }
}

// A file a command would change or remove: not protected (ATT), not selected (SPG).
void CheckWritable(const MemoryBackend::Entry& e, const std::string& shown) {
  if (e.is_protected) Refuse(Errc::kPermissionDenied, kWriteProtected, shown);
  if (e.is_selected)
    Refuse(Errc::kPermissionDenied, kInvalidOperation,
           shown + " is selected (SPG); release it with REL first");
}

std::optional<MemoryBackend::Entry> Find(MemoryBackend& store, const std::string& node,
                                         const std::string& name) {
  for (auto& e : store.List(node, name))
    if (e.name == name) return e;
  return std::nullopt;
}

std::string Pattern(const Operand& o) {
  return o.name.empty() ? "*" : o.name;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> out;
  std::size_t at = 0;
  while (at < text.size()) {
    std::size_t nl = text.find('\n', at);
    std::string line = text.substr(at, nl == std::string::npos ? std::string::npos : nl - at);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    out.push_back(std::move(line));
    if (nl == std::string::npos) break;
    at = nl + 1;
  }
  return out;
}

class Runner {
 public:
  Runner(MemoryBackend& store, std::string_view station, std::string_view command, bool confirm)
      : store_(store), station_(station), command_(command), confirm_(confirm) {}

  MemoryCommandResult Run() {
    Parsed p = Parse(command_);
    ops_ = p.operands;
    const std::string& m = p.mnemonic;
    if (m == "DIR") return Dir();
    if (m == "COP") return Cop();
    if (m == "REN") return Ren();
    if (m == "DEL") return Del();
    if (m == "ATT") return Att();
    if (m == "DIF") return Dif();
    if (m == "INI") return Ini();
    if (m == "SPG") return Spg();
    if (m == "REL") return Rel();
    Refuse(Errc::kInvalidArgument, kInvalid, command_);
  }

 private:
  void Count(std::size_t lo, std::size_t hi) {
    if (ops_.size() < lo || ops_.size() > hi) Refuse(Errc::kInvalidArgument, kSyntax, command_);
  }
  Operand Op(std::size_t i) { return ParseOperand(ops_.at(i), command_); }
  std::string Node(const Operand& o) { return MemoryNamespace(station_, o.device); }
  MemoryCommandResult Done() {
    MemoryCommandResult r;
    r.message = kExecuted;
    return r;
  }
  MemoryBackend::Entry MustFind(const std::string& node, const Operand& o) {
    auto e = Find(store_, node, o.name);
    if (!e) Refuse(Errc::kNotFound, kNotFound, o.Shown());
    return *e;
  }

  // DIR[,pattern][/MPx] (ln 1740-1760, 2033-2062, 7893-7916): name and sectors of 128 bytes; hidden files
  // (ATT HIDDEN) are left out.
  MemoryCommandResult Dir() {
    Count(0, 1);
    Operand o;
    if (!ops_.empty()) {
      std::string op = ops_[0];
      // "DIR,MP2": a memory without its slash.
      if (op.size() == 3 && op.rfind("MP", 0) == 0 && op.find('/') == std::string::npos) op = "/" + op;
      o = ParseOperand(op, command_);
    }
    const std::string node = Node(o);
    MemoryCommandResult r;
    std::size_t n = 0;
    r.lines.push_back("NAME   SECT");
    for (const auto& e : store_.List(node, Pattern(o))) {
      if (e.is_hidden) continue;
      const std::uint64_t sectors = std::max<std::uint64_t>(1, (e.size + 127) / 128);
      r.lines.push_back(fmt::format("{:<6} {:>4}{}", e.name, sectors, e.is_protected ? " P" : ""));
      ++n;
    }
    r.lines.push_back(fmt::format("{} FILE{}", n, n == 1 ? "" : "S"));
    r.message = kExecuted;
    return r;
  }

  // COP,SRC[/dev],DST[/dev] (ln 2064-2082, 7918-7930, 7988-8020).
  MemoryCommandResult Cop() {
    Count(1, 2);
    Operand src = Op(0);
    const std::string from = Node(src);
    if (ops_.size() == 1) {  // COP,NAME: the file on the screen
      if (src.wild()) Refuse(Errc::kInvalidArgument, kSyntax, command_);
      MustFind(from, src);
      auto text = store_.Get(from, src.name);
      if (!text) Refuse(Errc::kNotFound, kNotFound, src.Shown());
      MemoryCommandResult r;
      r.lines = Lines(*text);
      r.message = kDisplayed;
      return r;
    }
    Operand dst = Op(1);
    const std::string to = Node(dst);
    std::vector<std::pair<std::string, std::string>> copies;  // source name, destination name
    if (src.wild()) {
      // Wildcards copy under the same names (ln 7988-8020): "COP,A*/MP,B*/HDO" is FILMS1 10, a single
      // destination name for several files FILMS1 14.
      if (dst.name.find('*') != std::string::npos) Refuse(Errc::kInvalidArgument, kSyntax, command_);
      if (!dst.name.empty()) Refuse(Errc::kInvalidArgument, kIllegal, command_ + ": several files onto one");
      if (from == to) Refuse(Errc::kInvalidArgument, kIllegal, command_ + ": onto the same memory");
      for (const auto& e : store_.List(from, Pattern(src))) copies.emplace_back(e.name, e.name);
      if (copies.empty()) Refuse(Errc::kNotFound, kNotFound, src.Shown());
    } else {
      MustFind(from, src);
      const std::string name = dst.name.empty() ? src.name : dst.name;
      if (dst.name.find('*') != std::string::npos) Refuse(Errc::kInvalidArgument, kSyntax, command_);
      if (from == to && name == src.name)
        Refuse(Errc::kInvalidArgument, kIllegal, command_ + ": a file onto itself");
      copies.emplace_back(src.name, name);
    }
    // Every destination is checked before anything is copied: a refusal changes nothing.
    std::vector<bool> force;
    for (const auto& [s, d] : copies) {
      CheckNewName(to, d, command_);
      auto existing = Find(store_, to, d);
      if (existing) {
        const std::string shown = d + "/" + (dst.has_device ? dst.device : "MP1");
        CheckWritable(*existing, shown);
        if (!confirm_) Refuse(Errc::kAlreadyExists, kExists, shown + " (answer Y with --yes)");
      }
      force.push_back(existing.has_value());
    }
    CheckRoom(from, to, copies);
    for (std::size_t i = 0; i < copies.size(); ++i)
      store_.Copy(from, copies[i].first, to, copies[i].second, force[i]);
    MemoryCommandResult r = Done();
    for (const auto& [s, d] : copies) r.lines.push_back(s + " -> " + d);
    return r;
  }

  // The destination memory holds kMemoryCapacity characters (the user memory, ln 223; judgement call 35):
  // a copy that would overfill it is FILMS3 15 "the specified destination device is full" (ln 9758-9759),
  // checked before anything is copied. HOST (the control's hard disk) has no such bound.
  void CheckRoom(const std::string& from, const std::string& to,
                 const std::vector<std::pair<std::string, std::string>>& copies) {
    if (IsHost(to)) return;
    std::map<std::string, std::uint64_t> sizes;  // the destination memory after the copy, by name
    for (const auto& e : store_.List(to, "*")) sizes[e.name] = e.size;
    for (const auto& [s, d] : copies) sizes[d] = MustFind(from, Operand{s, "", false}).size;
    std::uint64_t used = 0;
    for (const auto& [name, size] : sizes) used += size;
    if (used > kMemoryCapacity)
      Refuse(Errc::kFailedPrecondition, kNoFreeSectors,
             fmt::format("{}: the memory would hold {} characters, {} at most (ln 223)", command_, used,
                         kMemoryCapacity));
  }

  // REN,OLD[/dev],NEW (ln 2084-2090, 7934-7939): in the same memory.
  MemoryCommandResult Ren() {
    Count(2, 2);
    Operand old_name = Op(0);
    Operand new_name = Op(1);
    if (old_name.wild() || new_name.wild()) Refuse(Errc::kInvalidArgument, kSyntax, command_);
    const std::string node = Node(old_name);
    if (new_name.has_device && Node(new_name) != node)
      Refuse(Errc::kInvalidArgument, kIllegal, command_ + ": a rename stays in its memory");
    CheckWritable(MustFind(node, old_name), old_name.Shown());
    CheckNewName(node, new_name.name, command_);
    if (Find(store_, node, new_name.name))
      Refuse(Errc::kAlreadyExists, kIllegal, command_ + ": " + new_name.name + " exists");
    store_.Rename(node, old_name.name, new_name.name);
    return Done();
  }

  // The files a DEL/ATT operand names: one file, a wildcard, or the whole memory ([ALL]).
  std::vector<MemoryBackend::Entry> Targets(const Operand& o, const std::string& node) {
    if (!o.wild()) return {MustFind(node, o)};
    auto all = store_.List(node, Pattern(o));
    if (all.empty() && !o.name.empty()) Refuse(Errc::kNotFound, kNotFound, o.Shown());
    return all;
  }

  // DEL,NAME[/MPx]; DEL,/MPx or DEL,*/MPx = [ALL], which asks FILMS2 02 (ln 1845-1863, 2092-2098).
  MemoryCommandResult Del() {
    Count(1, 1);
    Operand o = Op(0);
    const std::string node = Node(o);
    if ((o.name.empty() || o.name == "*") && !confirm_)
      Refuse(Errc::kFailedPrecondition, kConfirm,
             command_ + " deletes every file of the memory (answer Y with --yes)");
    auto targets = Targets(o, node);
    for (const auto& e : targets) CheckWritable(e, e.name);
    for (const auto& e : targets) store_.Delete(node, e.name);
    MemoryCommandResult r = Done();
    for (const auto& e : targets) r.lines.push_back(e.name);
    return r;
  }

  // ATT,NAME,100 protect, ATT,NAME,0 unprotect (ln 2131-2132); the menu's PROTECT, DISPROT (clears PROTECT
  // and HIDDEN) and HIDDEN (ln 1814-1843) by name.
  MemoryCommandResult Att() {
    Count(2, 2);
    Operand o = Op(0);
    const std::string node = Node(o);
    const std::string what(Trim(ops_[1]));
    auto targets = Targets(o, node);
    for (const auto& e : targets) {
      if (what == "100" || what == "PROTECT") {
        store_.Flag(node, e.name, "protected", true);
      } else if (what == "0" || what == "DISPROT") {
        store_.Flag(node, e.name, "protected", false);
        store_.Flag(node, e.name, "hidden", false);
      } else if (what == "HIDDEN") {
        store_.Flag(node, e.name, "hidden", true);
      } else {
        Refuse(Errc::kInvalidArgument, kSyntax,
               command_ + ": the attribute is 100, 0, PROTECT, DISPROT or HIDDEN");
      }
    }
    return Done();
  }

  // DIF,NAME/MP2,NAME/HD (ln 2133-2134, 7970-7986): on a difference the control asks FILMS2 09; here every
  // differing line is listed.
  MemoryCommandResult Dif() {
    Count(2, 2);
    Operand a = Op(0);
    Operand b = Op(1);
    if (b.name.empty()) b.name = a.name;
    if (a.wild() || b.wild()) Refuse(Errc::kInvalidArgument, kSyntax, command_);
    auto ta = store_.Get(Node(a), a.name);
    if (!ta) Refuse(Errc::kNotFound, kNotFound, a.Shown());
    auto tb = store_.Get(Node(b), b.name);
    if (!tb) Refuse(Errc::kNotFound, kNotFound, b.Shown());
    const auto la = Lines(*ta);
    const auto lb = Lines(*tb);
    MemoryCommandResult r;
    for (std::size_t i = 0; i < std::max(la.size(), lb.size()); ++i) {
      const std::string x = i < la.size() ? la[i] : "(end of file)";
      const std::string y = i < lb.size() ? lb[i] : "(end of file)";
      if (x == y) continue;
      r.lines.push_back(fmt::format("{}: < {}", i + 1, x));
      r.lines.push_back(fmt::format("{}: > {}", i + 1, y));
    }
    r.differ = !r.lines.empty();
    r.message = r.differ ? kContinue : kExecuted;
    return r;
  }

  // INI,NAME,/MPx (ln 7948-7957): erases the memory, its offsets, origins and tool-life files too; asks
  // FILMS2 02. A selected program stops it (nothing is erased).
  MemoryCommandResult Ini() {
    Count(2, 2);
    Operand dev = Op(1);
    if (!dev.name.empty() || !dev.has_device) Refuse(Errc::kInvalidArgument, kSyntax, command_);
    const std::string node = Node(dev);
    if (!confirm_)
      Refuse(Errc::kFailedPrecondition, kConfirm, command_ + " erases the memory (answer Y with --yes)");
    auto all = store_.List(node, "*");
    for (const auto& e : all)
      if (e.is_selected) CheckWritable(e, e.name);
    for (const auto& e : all) {
      if (e.is_protected) store_.Flag(node, e.name, "protected", false);
      store_.Delete(node, e.name);
    }
    MemoryCommandResult r = Done();
    r.lines.push_back(fmt::format("{} FILE{} ERASED", all.size(), all.size() == 1 ? "" : "S"));
    return r;
  }

  // SPG,NAME[/dev] (ln 2202, 8873-8888): one selected program per station; it cannot be edited or deleted
  // until REL (ln 1913, 2203).
  MemoryCommandResult Spg() {
    Count(1, 1);
    Operand o = Op(0);
    if (o.wild()) Refuse(Errc::kInvalidArgument, kSyntax, command_);
    const std::string node = Node(o);
    if (IsHost(node))
      Refuse(Errc::kInvalidArgument, kPeripheral, command_ + ": select from a memory MP0-MP6");
    MustFind(node, o);
    ReleaseAll(node, o.name);
    store_.Flag(node, o.name, "selected", true);
    return Done();
  }

  MemoryCommandResult Rel() {
    Count(0, 0);
    MemoryCommandResult r = Done();
    for (const auto& name : ReleaseAll("", "")) r.lines.push_back(name);
    return r;
  }

  // Releases every selected program of the station but `keep` in `keep_node`; returns what it released.
  std::vector<std::string> ReleaseAll(const std::string& keep_node, const std::string& keep) {
    std::vector<std::string> released;
    for (const std::string& node : StationMemories(station_)) {
      std::vector<MemoryBackend::Entry> entries;
      try {
        entries = store_.List(node, "*");
      } catch (const Error& e) {
        if (e.code() == Errc::kNotFound) continue;  // a memory the store does not hold
        throw;
      }
      for (const auto& e : entries) {
        if (!e.is_selected || (node == keep_node && e.name == keep)) continue;
        store_.Flag(node, e.name, "selected", false);
        released.push_back(node + ":" + e.name);
      }
    }
    return released;
  }

  MemoryBackend& store_;
  std::string station_;
  std::string command_;
  bool confirm_;
  std::vector<std::string> ops_;
};

}  // namespace

std::string MemoryNamespace(std::string_view station, std::string_view memory) {
  if (memory.empty() || memory == "MP1") return std::string(station);
  if (memory == "HOST" || memory == "HD" || memory == "HDO") return std::string(kHostNamespace);
  if (memory.size() == 3 && memory.substr(0, 2) == "MP" && memory[2] >= '0' && memory[2] <= '6')
    return std::string(station) + "/" + std::string(memory);
  Refuse(Errc::kInvalidArgument, kPeripheral,
         fmt::format("/{} is not a memory of the cell (MP0-MP6, HOST)", memory));
}

bool IsMemoryProgramName(std::string_view name) {
  if (name.empty() || name.size() > 6 || !(name[0] >= 'A' && name[0] <= 'Z')) return false;
  return std::all_of(name.begin(), name.end(),
                     [](char c) { return (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9'); });
}

std::vector<MemoryBackend::Entry> StoreMemory::List(const std::string& node, const std::string& pattern) {
  std::vector<Entry> out;
  for (const FileInfo& f : store_.List(node, pattern))
    out.push_back({f.name, f.metadata.size, f.is_protected, f.is_selected, f.is_hidden});
  return out;
}

std::optional<std::string> StoreMemory::Get(const std::string& node, const std::string& name) {
  try {
    return store_.Get(node, name).content;
  } catch (const Error& e) {
    if (e.code() == Errc::kNotFound) return std::nullopt;
    throw;
  }
}

void StoreMemory::Copy(const std::string& from_node, const std::string& from, const std::string& to_node,
                       const std::string& to, bool force) {
  CopyRequest c;
  c.from_node = from_node;
  c.from_name = from;
  c.to_node = to_node;
  c.to_name = to;
  c.force = force;
  store_.Copy(c);
}

void StoreMemory::Rename(const std::string& node, const std::string& from, const std::string& to) {
  RenameRequest r;
  r.node = node;
  r.name = from;
  r.to_name = to;
  store_.Rename(r);
}

void StoreMemory::Delete(const std::string& node, const std::string& name) {
  store_.Delete(node, name);
}

void StoreMemory::Flag(const std::string& node, const std::string& name, const std::string& flag, bool on) {
  const FileFlag f = flag == "selected" ? FileFlag::kSelected
                     : flag == "hidden" ? FileFlag::kHidden
                                        : FileFlag::kProtected;
  store_.SetFlag(node, name, f, on);
}

MemoryCommandResult RunMemoryCommand(MemoryBackend& store, std::string_view station, std::string_view command,
                                     bool confirm) {
  return Runner(store, station, command, confirm).Run();
}

}  // namespace cell::program_store
