#include "cell/config/config.h"

#include <fmt/format.h>
#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <toml++/toml.h>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <set>
#include <system_error>

#include "cell/config/dds.h"
#include "cell/error/error.h"
#include "cell/names/names.h"
#include "cell/toml/parse.h"

#ifndef CELL_CONFIG_SOURCE_DIR
#error "CELL_CONFIG_SOURCE_DIR must name the source tree (set by common/config/CMakeLists.txt)"
#endif

namespace fs = std::filesystem;

namespace cell::config {
namespace {

std::string Env(const char* name) {
  const char* v = std::getenv(name);
  return v == nullptr ? std::string() : std::string(v);
}

bool IsUnder(const fs::path& p, const fs::path& root) {
  auto [r, q] = std::mismatch(root.begin(), root.end(), p.begin(), p.end());
  return r == root.end() && q != p.end();
}

// A dialect named without rules: what any registry name looks like (the registry decides the rest).
bool IsDialectName(std::string_view name) {
  return !name.empty() && name.size() <= 32 && std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  });
}

// A located error: "<file>:<line>: <text>".
[[noreturn]] void Fail(const fs::path& file, const toml::node* where, const std::string& text) {
  if (where != nullptr && where->source().begin.line > 0) {
    throw Error(Errc::kInvalidArgument,
                fmt::format("{}:{}: {}", file.string(), where->source().begin.line, text));
  }
  throw Error(Errc::kInvalidArgument, fmt::format("{}: {}", file.string(), text));
}

std::string_view TypeName(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a float";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "an array";
    default:
      return "a date/time";
  }
}

std::string GetString(const fs::path& file, const toml::node& n, std::string_view key) {
  if (!n.is_string()) Fail(file, &n, fmt::format("{} must be a string, not {}", key, TypeName(n)));
  return std::string(*n.value<std::string_view>());
}

double GetNumber(const fs::path& file, const toml::node& n, std::string_view key) {
  if (n.is_integer()) return static_cast<double>(*n.value<int64_t>());
  if (n.is_floating_point()) return *n.value<double>();
  Fail(file, &n, fmt::format("{} must be a number, not {}", key, TypeName(n)));
}

tooltable::ToolEntry ParseTool(const fs::path& file, const toml::node& entry, size_t index) {
  const std::string where = fmt::format("[[tools]] entry {}", index + 1);
  const toml::table* t = entry.as_table();
  if (t == nullptr) Fail(file, &entry, fmt::format("{} must be a table", where));
  static const std::set<std::string, std::less<>> kKeys = {
      "tool",        "socket",   "length",   "diameter",    "life_left_min",
      "length_axis", "x_offset", "z_offset", "nose_radius", "tip"};
  for (auto&& [k, v] : *t) {
    if (!kKeys.contains(k.str())) {
      Fail(file, &v,
           fmt::format(
               "{}: unknown key '{}' (allowed: tool, socket, length, diameter, life_left_min, length_axis, "
               "x_offset, z_offset, nose_radius, tip)",
               where, k.str()));
    }
  }
  auto require = [&](std::string_view key) -> const toml::node& {
    const toml::node* n = t->get(key);
    if (n == nullptr) Fail(file, &entry, fmt::format("{}: missing key '{}'", where, key));
    return *n;
  };
  tooltable::ToolEntry tool;
  const toml::node& tn = require("tool");
  if (tn.is_integer()) {
    tool.tool = fmt::format("{}", *tn.value<int64_t>());
  } else if (tn.is_string()) {
    tool.tool = std::string(*tn.value<std::string_view>());
  } else {
    Fail(file, &tn,
         fmt::format("{}: tool must be a string such as \"1001\" or \"33412.5\" (or an integer), not {}",
                     where, TypeName(tn)));
  }
  if (!IsValidToolNumber(tool.tool)) {
    Fail(file, &tn,
         fmt::format("{}: tool = '{}': must be 1-7 digits with an optional suffix .1-.7, e.g. \"33412.5\"",
                     where, tool.tool));
  }
  const toml::node& sn = require("socket");
  if (!sn.is_integer() || *sn.value<int64_t>() < 1 || *sn.value<int64_t>() > 9999) {
    Fail(file, &sn, fmt::format("{} (tool {}): socket must be an integer in 1..9999", where, tool.tool));
  }
  tool.socket = static_cast<int>(*sn.value<int64_t>());
  // Compensations and offsets are signed (the KT-APL manual's example E45 has D-.25); life and nose radius
  // are not.
  auto number = [&](std::string_view key, double& out, bool non_negative) {
    const toml::node* n = t->get(key);
    if (n == nullptr) return;
    out = GetNumber(file, *n, fmt::format("{} (tool {}): {}", where, tool.tool, key));
    if (!std::isfinite(out) || (non_negative && out < 0)) {
      Fail(file, n,
           fmt::format("{} (tool {}): {} = {}: must be a {}number", where, tool.tool, key, out,
                       non_negative ? "non-negative " : "finite "));
    }
  };
  number("length", tool.length, false);
  number("diameter", tool.diameter, false);
  number("life_left_min", tool.life_left_min, true);
  number("x_offset", tool.x_offset, false);
  number("z_offset", tool.z_offset, false);
  number("nose_radius", tool.nose_radius, true);
  if (const toml::node* n = t->get("tip")) {
    if (!n->is_integer() || *n->value<int64_t>() < 0 || *n->value<int64_t>() > 9) {
      Fail(file, n, fmt::format("{} (tool {}): tip must be a tip position code 0..9", where, tool.tool));
    }
    tool.tip = static_cast<int>(*n->value<int64_t>());
  }
  if (const toml::node* n = t->get("length_axis")) {
    std::string a = GetString(file, *n, fmt::format("{} (tool {}): length_axis", where, tool.tool));
    if (a != "X" && a != "Y" && a != "Z") {
      Fail(file, n,
           fmt::format("{} (tool {}): length_axis = '{}': must be \"X\", \"Y\" or \"Z\"", where, tool.tool,
                       a));
    }
    tool.length_axis = a[0];
  }
  return tool;
}

// An M code key of an [[io.aux]] entry: absent -1, else an integer 0..999.
int AuxMCode(const fs::path& file, const toml::table& t, std::string_view key, const std::string& where) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return -1;
  if (!n->is_integer() || *n->value<int64_t>() < 0 || *n->value<int64_t>() > 999)
    Fail(file, n, fmt::format("{}: {} must be an M code, an integer in 0..999", where, key));
  return static_cast<int>(*n->value<int64_t>());
}

config::AuxOutput ParseAux(const fs::path& file, const toml::node& entry, size_t index) {
  const std::string where = fmt::format("[[io.aux]] entry {}", index + 1);
  const toml::table* t = entry.as_table();
  if (t == nullptr) Fail(file, &entry, fmt::format("{} must be a table", where));
  static const std::set<std::string, std::less<>> kKeys = {
      "name", "output", "m_on", "m_off", "interlock", "interlock_on", "interlock_off", "note"};
  for (auto&& [k, v] : *t) {
    if (!kKeys.contains(k.str())) {
      Fail(file, &v,
           fmt::format("{}: unknown key '{}' (allowed: name, output, m_on, m_off, interlock, interlock_on, "
                       "interlock_off, note)",
                       where, k.str()));
    }
  }
  config::AuxOutput a;
  const toml::node* name = t->get("name");
  if (name == nullptr) Fail(file, &entry, fmt::format("{}: missing key 'name'", where));
  a.name = GetString(file, *name, where + ": name");
  if (a.name.empty() || a.name.size() > 32)
    Fail(file, name, fmt::format("{}: name is 1-32 characters", where));
  const toml::node* out = t->get("output");
  if (out == nullptr) Fail(file, &entry, fmt::format("{} ({}): missing key 'output'", where, a.name));
  a.output = GetString(file, *out, where + ": output");
  if (!IsValidIoName(a.output)) {
    Fail(file, out,
         fmt::format("{} ({}): output = '{}': must be 1-16 of A-Z, 0-9, '_', '.', '[', ']' starting with a "
                     "letter",
                     where, a.name, a.output));
  }
  a.m_on = AuxMCode(file, *t, "m_on", where);
  a.m_off = AuxMCode(file, *t, "m_off", where);
  if (a.m_on < 0 && a.m_off < 0)
    Fail(file, &entry, fmt::format("{} ({}): give m_on, m_off or both", where, a.name));
  if (const toml::node* n = t->get("interlock")) {
    if (!n->is_boolean()) Fail(file, n, fmt::format("{}: interlock must be true or false", where));
    a.interlock = *n->value<bool>();
  }
  if (const toml::node* n = t->get("note")) {
    a.note = GetString(file, *n, where + ": note");
    if (a.note.size() > 80)
      Fail(file, n, fmt::format("{} ({}): note is at most 80 characters", where, a.name));
  }
  a.interlock_on = AuxMCode(file, *t, "interlock_on", where);
  a.interlock_off = AuxMCode(file, *t, "interlock_off", where);
  if (!a.interlock && (a.interlock_on >= 0 || a.interlock_off >= 0))
    Fail(file, &entry,
         fmt::format("{} ({}): interlock_on / interlock_off need interlock = true", where, a.name));
  return a;
}

// [io]: only [[io.aux]]; each M code means one thing across the entries.
std::vector<config::AuxOutput> ParseIo(const fs::path& file, const toml::node& io) {
  const toml::table* t = io.as_table();
  if (t == nullptr) Fail(file, &io, "io must be a table [io]");
  for (auto&& [k, v] : *t)
    if (k.str() != "aux") Fail(file, &v, fmt::format("[io]: unknown key '{}' (allowed: aux)", k.str()));
  std::vector<config::AuxOutput> out;
  const toml::node* an = t->get("aux");
  if (an == nullptr) return out;
  const toml::array* arr = an->as_array();
  if (arr == nullptr) Fail(file, an, "io.aux must be an array of tables [[io.aux]]");
  std::map<int, std::string> used;  // M code -> the entry's name
  for (size_t i = 0; i < arr->size(); ++i) {
    const toml::node& entry = *arr->get(i);
    config::AuxOutput a = ParseAux(file, entry, i);
    for (int m : {a.m_on, a.m_off, a.interlock_on, a.interlock_off}) {
      if (m < 0) continue;
      if (auto [it, fresh] = used.emplace(m, a.name); !fresh)
        Fail(
            file, &entry,
            fmt::format("[[io.aux]] entry {} ({}): M{} is already used by {}", i + 1, a.name, m, it->second));
    }
    out.push_back(std::move(a));
  }
  return out;
}

// [serial]: the keys and their types; the values against the control are cell-dnc's (cell::dnc::Resolve).
config::SerialTable ParseSerial(const fs::path& file, const toml::node& node) {
  const toml::table* t = node.as_table();
  if (t == nullptr) Fail(file, &node, "serial must be a table [serial]");
  static const std::set<std::string, std::less<>> kInts = {"baud", "data_bits", "stop_bits", "leader",
                                                           "memory"};
  static const std::set<std::string, std::less<>> kTexts = {"device", "parity", "code", "flow", "end"};
  config::SerialTable s;
  for (auto&& [k, v] : *t) {
    std::string key(k.str());
    if (kInts.contains(key)) {
      if (!v.is_integer())
        Fail(file, &v, fmt::format("[serial] {} must be an integer, not {}", key, TypeName(v)));
      int64_t n = *v.value<int64_t>();
      if (n < 0 || n > 1000000) Fail(file, &v, fmt::format("[serial] {} = {}: out of range", key, n));
      std::optional<int>& slot = key == "baud"        ? s.baud
                                 : key == "data_bits" ? s.data_bits
                                 : key == "stop_bits" ? s.stop_bits
                                 : key == "memory"    ? s.memory
                                                      : s.leader;
      slot = static_cast<int>(n);
    } else if (kTexts.contains(key)) {
      std::string text = GetString(file, v, "[serial] " + key);
      if (key == "device") {
        s.device = text;
      } else {
        (key == "parity" ? s.parity : key == "code" ? s.code : key == "flow" ? s.flow : s.end) = text;
      }
    } else {
      Fail(file, &v,
           fmt::format(
               "[serial]: unknown key '{}' (allowed: device, baud, data_bits, parity, stop_bits, code, "
               "flow, end, leader, memory)",
               key));
    }
  }
  if (s.device.empty() || s.device[0] != '/') {
    Fail(file, &node, "[serial]: device must be the line's absolute path (device = \"/dev/ttyS0\")");
  }
  return s;
}

std::string BaseTool(const std::string& tool) {
  return tool.substr(0, tool.find('.'));
}

}  // namespace

bool IsValidStationId(std::string_view id) {
  return names::IsStationId(id);
}

bool IsValidIoName(std::string_view name) {
  if (name.empty() || name.size() > 16 || name[0] < 'A' || name[0] > 'Z') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '[' || c == ']';
  });
}

bool IsValidToolNumber(std::string_view tool) {
  size_t dot = tool.find('.');
  std::string_view base = tool.substr(0, dot);
  if (base.empty() || base.size() > 7) return false;
  if (!std::all_of(base.begin(), base.end(), [](char c) { return c >= '0' && c <= '9'; })) return false;
  if (dot == std::string_view::npos) return true;
  std::string_view suffix = tool.substr(dot + 1);
  return suffix.size() == 1 && suffix[0] >= '1' && suffix[0] <= '7';
}

fs::path SourceTreeDir() {
  return CELL_CONFIG_SOURCE_DIR;
}

fs::path DefaultConfigDir(const fs::path& exe) {
  if (IsUnder(exe, "/usr") || IsUnder(exe, "/opt")) return "/etc/cell";
  return SourceTreeDir() / "deploy";
}

fs::path ConfigDir() {
  if (std::string dir = Env("CELL_CONFIG_DIR"); !dir.empty()) return dir;
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return DefaultConfigDir(ec ? fs::path() : exe);
}

fs::path DataDir() {
  fs::path dir;
  if (std::string d = Env("CELL_DATA_DIR"); !d.empty()) {
    dir = d;
  } else if (std::string x = Env("XDG_STATE_HOME"); !x.empty() && x.front() == '/') {
    dir = fs::path(x) / "cell";
  } else {
    std::string home = Env("HOME");
    if (home.empty()) {
      if (const passwd* pw = getpwuid(getuid()); pw != nullptr && pw->pw_dir != nullptr) home = pw->pw_dir;
    }
    if (home.empty()) {
      throw Error(Errc::kIo,
                  "cannot find a data directory: set CELL_DATA_DIR (HOME and XDG_STATE_HOME are unset)");
    }
    dir = fs::path(home) / ".local" / "state" / "cell";
  }
  std::error_code ec;
  // A directory made here is its owner's only (0700): state, databases and logs of a local cell are private.
  // Under systemd StateDirectory= makes /var/lib/cell (0750, group cell) and this leaves it as it is.
  if (!fs::exists(dir, ec)) {
    fs::create_directories(dir.parent_path(), ec);
    if (mkdir(dir.c_str(), 0700) != 0 && errno != EEXIST)
      ec = std::error_code(errno, std::generic_category());
  }
  if (ec || !fs::is_directory(dir)) {
    throw Error(Errc::kIo, fmt::format("cannot create data directory {}: {}", dir.string(),
                                       ec ? ec.message() : "not a directory"));
  }
  return dir;
}

int Domain() {
  std::string v = Env("CELL_DOMAIN");
  if (v.empty()) return kDefaultDomain;
  bool digits = v.size() <= 3 && std::all_of(v.begin(), v.end(), [](char c) { return c >= '0' && c <= '9'; });
  int d = digits ? std::stoi(v) : -1;
  if (d < 0 || d > kMaxDomain) {
    throw Error(Errc::kInvalidArgument,
                fmt::format("CELL_DOMAIN='{}': must be a DDS domain id, an integer in 0..{} (default {})", v,
                            kMaxDomain, kDefaultDomain));
  }
  return d;
}

bool SecurityOn() {
  const std::string v = Env("CELL_SECURITY");
  if (v.empty() || v == "off") return false;
  if (v == "on") return true;
  throw Error(Errc::kInvalidArgument, fmt::format("CELL_SECURITY='{}': expected on or off (default off)",
                                                  cell::names::Shown(v, 20, false)));
}

std::string IdentityOverride() {
  return Env("CELL_IDENTITY");
}

std::vector<std::string> ListStations() {
  fs::path dir = ConfigDir() / "stations";
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw Error(Errc::kNotFound,
                fmt::format("no station directory {} (set CELL_CONFIG_DIR to the cell's configuration)",
                            dir.string()));
  }
  std::vector<std::string> ids;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() != ".toml" || !e.is_regular_file()) continue;
    std::string id = e.path().stem().string();
    if (IsValidStationId(id)) ids.push_back(id);
  }
  std::sort(ids.begin(), ids.end());
  return ids;
}

StationConfig LoadStation(std::string_view id, const DialectRules* rules) {
  names::CheckStation(id);
  fs::path file = ConfigDir() / "stations" / (std::string(id) + ".toml");
  std::error_code ec;
  if (!fs::exists(file, ec)) {
    std::string known;
    try {
      for (const auto& s : ListStations()) known += (known.empty() ? "" : ", ") + s;
    } catch (const Error&) {
    }
    throw Error(Errc::kNotFound, fmt::format("station '{}' is not configured: no file {} (configured: {})",
                                             id, file.string(), known.empty() ? "none" : known));
  }
  return LoadStationFile(file, rules);
}

StationConfig LoadStationFile(const fs::path& file, const DialectRules* rules) {
  toml::table root = tomlfile::ParseFile(file);
  StationConfig cfg;
  cfg.file = file;
  const toml::node* sn = root.get("station");
  if (sn == nullptr) Fail(file, nullptr, "missing table [station] (with id and dialect)");
  const toml::table* st = sn->as_table();
  if (st == nullptr) Fail(file, sn, "station must be a table [station]");
  for (auto&& [k, v] : *st) {
    if (k.str() != "id" && k.str() != "dialect" && k.str() != "description" && k.str() != "coded_pallets" &&
        k.str() != "dds") {
      Fail(file, &v,
           fmt::format("[station]: unknown key '{}' (allowed: id, dialect, description, coded_pallets, dds)",
                       k.str()));
    }
  }
  const toml::node* id = st->get("id");
  if (id == nullptr) Fail(file, sn, "[station]: missing key 'id'");
  cfg.id = GetString(file, *id, "[station] id");
  if (cfg.id != file.stem().string()) {
    Fail(file, id,
         fmt::format("[station] id = '{}': must equal the file name's stem '{}'", cfg.id,
                     file.stem().string()));
  }
  if (!IsValidStationId(cfg.id)) {
    Fail(file, id,
         fmt::format("[station] id = '{}': must be 1-16 characters of A-Z, a-z, 0-9, '_' or '-'", cfg.id));
  }
  const toml::node* dialect = st->get("dialect");
  if (dialect == nullptr) {
    Fail(file, sn,
         rules != nullptr ? fmt::format("[station]: missing key 'dialect' (one of {})", rules->names)
                          : std::string("[station]: missing key 'dialect'"));
  }
  cfg.dialect = GetString(file, *dialect, "[station] dialect");
  if (rules != nullptr) {
    std::string name = rules->canonical(cfg.dialect);
    if (name.empty()) {
      Fail(file, dialect,
           fmt::format("[station] dialect = '{}': must be one of {}", cfg.dialect, rules->names));
    }
    cfg.dialect = std::move(name);
  } else if (!IsDialectName(cfg.dialect)) {
    Fail(file, dialect,
         fmt::format("[station] dialect = '{}': must be a dialect name (1-32 letters, digits, '_' or '-')",
                     cfg.dialect.substr(0, 32)));
  }
  if (const toml::node* d = st->get("description"))
    cfg.description = GetString(file, *d, "[station] description");
  if (const toml::node* c = st->get("coded_pallets")) {
    if (!c->is_boolean())
      Fail(file, c, fmt::format("[station] coded_pallets must be true or false, not {}", TypeName(*c)));
    cfg.coded_pallets = *c->value<bool>();
  }
  if (const toml::node* d = st->get("dds")) {
    cfg.dds = GetString(file, *d, "[station] dds");
    if (!IsDdsVendor(cfg.dds))
      Fail(file, d, fmt::format("[station] dds = '{}': must be one of {}", cfg.dds, DdsVendorList()));
  }
  if (const toml::node* pn = root.get("params")) {
    // The dialect's machine settings (the interpreter's RunOptions::params), by the dialect's own names:
    // EMCO's operator monitor (O11 = 9, S01 = 2), ... Values are given to every run as text.
    const toml::table* pt = pn->as_table();
    if (pt == nullptr) Fail(file, pn, "params must be a table [params] of NAME = value");
    for (auto&& [k, v] : *pt) {
      std::string_view key = k.str();
      bool ok_key = !key.empty() && key.size() <= 32 && std::all_of(key.begin(), key.end(), [](char c) {
        return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' ||
               c == '.' || c == '-';
      });
      if (!ok_key) {
        Fail(file, &v, fmt::format("[params]: '{}': names are 1-32 letters, digits, '_', '.' or '-'", key));
      }
      std::string value;
      if (v.is_string()) {
        value = std::string(*v.value<std::string_view>());
      } else if (v.is_integer()) {
        value = fmt::format("{}", *v.value<int64_t>());
      } else if (v.is_floating_point()) {
        value = fmt::format("{}", *v.value<double>());
      } else if (v.is_boolean()) {
        value = *v.value<bool>() ? "1" : "0";
      } else {
        Fail(file, &v,
             fmt::format("[params] {}: must be a string, number or boolean, not {}", key, TypeName(v)));
      }
      cfg.params[std::string(key)] = std::move(value);
    }
  }
  if (const toml::node* io = root.get("io")) cfg.aux = ParseIo(file, *io);
  if (const toml::node* sn = root.get("serial")) cfg.serial = ParseSerial(file, *sn);
  if (const toml::node* tn = root.get("tools")) {
    const toml::array* arr = tn->as_array();
    if (arr == nullptr) Fail(file, tn, "tools must be an array of tables [[tools]]");
    std::map<std::string, size_t> by_tool;
    std::map<int, std::string> by_socket;  // socket -> base tool number
    for (size_t i = 0; i < arr->size(); ++i) {
      const toml::node& entry = *arr->get(i);
      tooltable::ToolEntry tool = ParseTool(file, entry, i);
      // The dialect's own ranges, as its tool-table form (KT-APL TLD) enforces them on every other path.
      if (std::string why = rules != nullptr ? rules->check_tool(cfg.dialect, tool) : std::string();
          !why.empty())
        Fail(file, &entry, fmt::format("[[tools]] entry {} (tool {}): {}", i + 1, tool.tool, why));
      if (auto [it, fresh] = by_tool.emplace(tool.tool, i); !fresh) {
        Fail(file, &entry,
             fmt::format("[[tools]] entry {}: tool {} is already listed in entry {}", i + 1, tool.tool,
                         it->second + 1));
      }
      std::string base = BaseTool(tool.tool);
      if (auto [it, fresh] = by_socket.emplace(tool.socket, base); !fresh && it->second != base) {
        Fail(file, &entry,
             fmt::format("[[tools]] entry {}: socket {} already holds tool {} (only suffix data "
                         "sets of one tool may share a socket)",
                         i + 1, tool.socket, it->second));
      }
      cfg.tools.push_back(std::move(tool));
    }
  }
  return cfg;
}

}  // namespace cell::config
