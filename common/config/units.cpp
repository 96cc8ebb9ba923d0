#include "cell/config/units.h"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <map>

#include "cell/error/error.h"

namespace fs = std::filesystem;

namespace cell::config {
namespace {

std::string_view Trim(std::string_view s) {
  size_t b = s.find_first_not_of(" \t\r\n");
  if (b == std::string_view::npos) return {};
  size_t e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

bool IsSpace(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

int HexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Environment variable references in one word: ${NAME} anywhere; a word that is exactly $NAME expands to
// the value split into words (systemd.service(5) "Command lines").
void SubstituteVariables(const std::string& word, const std::map<std::string, std::string>& env,
                         std::vector<std::string>& out) {
  auto is_name = [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  };
  if (word.size() > 1 && word[0] == '$' && word[1] != '{') {
    std::string name = word.substr(1);
    if (std::all_of(name.begin(), name.end(), is_name)) {
      if (auto it = env.find(name); it != env.end()) {
        for (auto& w : SplitWords(it->second)) out.push_back(w);
      }
      return;
    }
  }
  std::string result;
  for (size_t i = 0; i < word.size(); ++i) {
    if (word[i] == '$' && i + 1 < word.size() && word[i + 1] == '{') {
      size_t close = word.find('}', i + 2);
      if (close != std::string::npos) {
        std::string name = word.substr(i + 2, close - i - 2);
        if (auto it = env.find(name); it != env.end()) result += it->second;
        i = close;
        continue;
      }
    }
    result += word[i];
  }
  out.push_back(std::move(result));
}

}  // namespace

std::vector<std::string> UnitFile::Values(std::string_view section, std::string_view key) const {
  std::vector<std::string> out;
  for (const auto& e : entries) {
    if (e.section != section || e.key != key) continue;
    if (e.value.empty()) {
      out.clear();
    } else {
      out.push_back(e.value);
    }
  }
  return out;
}

std::optional<std::string> UnitFile::Value(std::string_view section, std::string_view key) const {
  std::optional<std::string> out;
  for (const auto& e : entries) {
    if (e.section == section && e.key == key) out = e.value;
  }
  return out;
}

UnitFile ParseUnitFile(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw Error(Errc::kNotFound, fmt::format("{}: cannot open unit file", file.string()));
  UnitFile unit;
  unit.path = file;
  std::string section;
  std::string raw;
  int lineno = 0;
  while (std::getline(in, raw)) {
    ++lineno;
    std::string_view line = Trim(raw);
    if (line.empty() || line[0] == '#' || line[0] == ';') continue;
    if (line.front() == '[') {
      if (line.back() != ']' || line.size() < 3) {
        throw Error(Errc::kInvalidArgument,
                    fmt::format("{}:{}: malformed section header", file.string(), lineno));
      }
      section = std::string(line.substr(1, line.size() - 2));
      continue;
    }
    size_t eq = line.find('=');
    if (eq == std::string_view::npos) {
      throw Error(Errc::kInvalidArgument,
                  fmt::format("{}:{}: expected key=value, got '{}'", file.string(), lineno, line));
    }
    if (section.empty()) {
      throw Error(Errc::kInvalidArgument,
                  fmt::format("{}:{}: assignment outside of a section", file.string(), lineno));
    }
    UnitFile::Entry e{section, std::string(Trim(line.substr(0, eq))), std::string(Trim(line.substr(eq + 1))),
                      lineno};
    // A trailing backslash continues the value on the next line (comment lines in between are skipped).
    while (!e.value.empty() && e.value.back() == '\\') {
      e.value.back() = ' ';
      std::string next;
      bool got = false;
      while (std::getline(in, next)) {
        ++lineno;
        std::string_view t = Trim(next);
        if (!t.empty() && (t[0] == '#' || t[0] == ';')) continue;
        e.value += std::string(t);
        got = true;
        break;
      }
      if (!got) break;
    }
    e.value = std::string(Trim(e.value));
    unit.entries.push_back(std::move(e));
  }
  return unit;
}

std::vector<std::string> SplitWords(std::string_view text) {
  std::vector<std::string> words;
  size_t i = 0;
  const size_t n = text.size();
  while (true) {
    while (i < n && IsSpace(text[i])) ++i;
    if (i >= n) break;
    std::string word;
    char quote = 0;
    if (text[i] == '"' || text[i] == '\'') quote = text[i++];
    bool closed = quote == 0;
    while (i < n) {
      char c = text[i];
      if (quote != 0 && c == quote) {
        closed = true;
        ++i;
        if (i < n && !IsSpace(text[i])) {
          throw Error(Errc::kInvalidArgument, fmt::format("'{}': a closing quote must end the word", text));
        }
        break;
      }
      if (quote == 0 && IsSpace(c)) break;
      if (c == '\\') {
        if (i + 1 >= n) throw Error(Errc::kInvalidArgument, fmt::format("'{}': trailing backslash", text));
        char e = text[i + 1];
        i += 2;
        switch (e) {
          case '\\':
            word += '\\';
            break;
          case '"':
            word += '"';
            break;
          case '\'':
            word += '\'';
            break;
          case 'n':
            word += '\n';
            break;
          case 't':
            word += '\t';
            break;
          case 'r':
            word += '\r';
            break;
          case 's':
            word += ' ';
            break;
          case 'x': {
            int hi = i < n ? HexDigit(text[i]) : -1;
            int lo = i + 1 < n ? HexDigit(text[i + 1]) : -1;
            if (hi < 0 || lo < 0)
              throw Error(Errc::kInvalidArgument, fmt::format("'{}': bad \\x escape", text));
            word += static_cast<char>(hi * 16 + lo);
            i += 2;
            break;
          }
          default:
            throw Error(Errc::kInvalidArgument, fmt::format("'{}': unsupported escape '\\{}'", text, e));
        }
        continue;
      }
      word += c;
      ++i;
    }
    if (!closed) throw Error(Errc::kInvalidArgument, fmt::format("'{}': unterminated quote", text));
    words.push_back(std::move(word));
  }
  return words;
}

std::string UnitName(const fs::path& unit_file, std::string_view instance) {
  std::string name = unit_file.filename().string();
  size_t at = name.find('@');
  size_t dot = name.rfind('.');
  bool is_template = at != std::string::npos && dot == at + 1;
  if (!is_template) return name;
  if (instance.empty()) {
    throw Error(Errc::kInvalidArgument,
                fmt::format("{} is a template unit: it needs an instance (a station id)", name));
  }
  return fmt::format("{}@{}{}", name.substr(0, at), instance, name.substr(dot));
}

std::string ExpandSpecifiers(std::string_view word, std::string_view unit_name) {
  std::string_view base = unit_name.substr(0, unit_name.rfind('.'));
  size_t at = base.find('@');
  std::string_view prefix = base.substr(0, at);
  std::string_view instance = at == std::string_view::npos ? std::string_view() : base.substr(at + 1);
  std::string out;
  for (size_t i = 0; i < word.size(); ++i) {
    if (word[i] != '%') {
      out += word[i];
      continue;
    }
    if (i + 1 >= word.size())
      throw Error(Errc::kInvalidArgument, fmt::format("'{}': lone '%' at the end", word));
    char s = word[++i];
    switch (s) {
      case '%':
        out += '%';
        break;
      case 'i':
      case 'I':
        out += instance;
        break;
      case 'n':
        out += unit_name;
        break;
      case 'N':
        out += base;
        break;
      case 'p':
      case 'P':
        out += prefix;
        break;
      default:
        throw Error(Errc::kUnimplemented,
                    fmt::format("'{}': specifier %{} is not supported (only %i %I %n %N %p %P %%)", word, s));
    }
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> EnvironmentFor(const fs::path& unit_file,
                                                                std::string_view instance) {
  UnitFile unit = ParseUnitFile(unit_file);
  std::string name = UnitName(unit_file, instance);
  std::vector<std::pair<std::string, std::string>> env;
  for (const auto& value : unit.Values("Service", "Environment")) {
    for (const auto& word : SplitWords(value)) {
      std::string assignment = ExpandSpecifiers(word, name);
      size_t eq = assignment.find('=');
      if (eq == 0 || eq == std::string::npos) {
        throw Error(Errc::kInvalidArgument,
                    fmt::format("{}: Environment entry '{}' is not NAME=VALUE", unit_file.string(), word));
      }
      env.emplace_back(assignment.substr(0, eq), assignment.substr(eq + 1));
    }
  }
  return env;
}

std::vector<std::string> ExecStartFor(const fs::path& unit_file, std::string_view instance,
                                      const fs::path& bin_dir) {
  UnitFile unit = ParseUnitFile(unit_file);
  std::string name = UnitName(unit_file, instance);
  std::vector<std::string> lines = unit.Values("Service", "ExecStart");
  if (lines.size() != 1) {
    throw Error(Errc::kInvalidArgument, fmt::format("{}: expected exactly one ExecStart=, found {}",
                                                    unit_file.string(), lines.size()));
  }
  std::string_view cmd = lines[0];
  // Prefixes: @ (argv[0] given separately), - (ignore failure), : (no substitution), + ! (privileges).
  bool at_prefix = false, substitute = true;
  while (!cmd.empty() &&
         (cmd[0] == '@' || cmd[0] == '-' || cmd[0] == ':' || cmd[0] == '+' || cmd[0] == '!')) {
    if (cmd[0] == '@') at_prefix = true;
    if (cmd[0] == ':') substitute = false;
    cmd.remove_prefix(1);
  }
  std::map<std::string, std::string> env;
  if (substitute) {
    for (auto& [k, v] : EnvironmentFor(unit_file, instance)) env[k] = v;
  }
  std::vector<std::string> argv;
  for (const auto& word : SplitWords(cmd)) {
    std::string expanded = ExpandSpecifiers(word, name);
    if (substitute) {
      SubstituteVariables(expanded, env, argv);
    } else {
      argv.push_back(std::move(expanded));
    }
  }
  if (at_prefix && argv.size() >= 2) argv.erase(argv.begin() + 1);  // drop the given argv[0]; exec the path
  if (argv.empty())
    throw Error(Errc::kInvalidArgument, fmt::format("{}: ExecStart= is empty", unit_file.string()));
  if (!bin_dir.empty()) argv[0] = (bin_dir / fs::path(argv[0]).filename()).string();
  return argv;
}

std::vector<UnitCommand> CellCommands(const fs::path& unit_dir, const std::vector<std::string>& stations,
                                      const fs::path& bin_dir, const StationHasTable& has_table) {
  std::vector<fs::path> plain, templates;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(unit_dir, ec)) {
    std::string name = e.path().filename().string();
    if (e.path().extension() != ".service") continue;
    (name.find("@.") != std::string::npos ? templates : plain).push_back(e.path());
  }
  if (plain.empty() && templates.empty()) {
    throw Error(Errc::kNotFound, fmt::format("no *.service units in {}", unit_dir.string()));
  }
  std::sort(plain.begin(), plain.end());
  std::sort(templates.begin(), templates.end());
  std::vector<UnitCommand> out;
  for (const auto& f : plain) out.push_back({UnitName(f, ""), ExecStartFor(f, "", bin_dir)});
  std::vector<std::optional<std::string>> needs;  // each template's X-CellStationTable
  for (const auto& f : templates) needs.push_back(ParseUnitFile(f).Value("Unit", "X-CellStationTable"));
  for (const auto& station : stations) {
    for (size_t i = 0; i < templates.size(); ++i) {
      if (needs[i] && !(has_table && has_table(station, *needs[i]))) continue;
      out.push_back({UnitName(templates[i], station), ExecStartFor(templates[i], station, bin_dir)});
    }
  }
  return out;
}

}  // namespace cell::config
