// A reader for the cell's systemd unit files (deploy/systemd/), so that `cellctl up` starts the very
// command lines systemd would run, with the install paths mapped into the build tree.
//
//   auto argv = cell::config::ExecStartFor(src / "deploy/systemd/cell-interpreter@.service", "KT01",
//                                          build / "bin");
//   // {"<build>/bin/cell-interpreter", "--station", "KT01"}
//
// It understands what systemd.syntax(7) and systemd.service(5) define for these keys: sections, comments,
// backslash line continuation, empty assignments resetting a list, ExecStart prefixes (@ - : + !),
// double/single quoting and C escapes in words, the specifiers %i %I %n %N %p %P %%, and ${VAR} / $VAR
// from the unit's own Environment=. Anything else it cannot reproduce faithfully (other specifiers, a
// template without an instance) is an error rather than a guess.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace cell::config {

struct UnitFile {
  struct Entry {
    std::string section;
    std::string key;
    std::string value;  // continuation lines joined with one space; surrounding whitespace trimmed
    int line = 0;       // 1-based line of the key
  };
  std::filesystem::path path;
  std::vector<Entry> entries;

  // Values of a list-valued key in order; an empty assignment clears the values before it.
  std::vector<std::string> Values(std::string_view section, std::string_view key) const;
  // The last assignment of a key, if any.
  std::optional<std::string> Value(std::string_view section, std::string_view key) const;
};

// Reads a unit file. Throws cell::Error: kNotFound if it does not exist, kInvalidArgument (naming file and
// line) for a line that is neither a section, a comment nor key=value, or a key before any section.
UnitFile ParseUnitFile(const std::filesystem::path& file);

// systemd's word splitting: whitespace separates words; "..." and '...' quote (only at the start of a
// word); C escapes (\\ \" \' \n \t \r \s \xNN) are decoded. Throws cell::Error(kInvalidArgument) on an
// unterminated quote or unknown escape.
std::vector<std::string> SplitWords(std::string_view text);

// The unit name systemd would give `unit_file` for `instance`: "cell-interpreter@KT01.service" for a
// template, the file name otherwise (instance ignored). Throws kInvalidArgument for a template without an
// instance.
std::string UnitName(const std::filesystem::path& unit_file, std::string_view instance);

// Replaces %i %I (instance) %n (unit name) %N (without suffix) %p %P (prefix, before '@') and %% in one
// word. Throws cell::Error(kUnimplemented) for any other specifier.
std::string ExpandSpecifiers(std::string_view word, std::string_view unit_name);

// The argv of the unit's (single) ExecStart for `instance`, with argv[0]'s directory replaced by bin_dir
// (unless bin_dir is empty). Throws cell::Error(kInvalidArgument) when the unit has no ExecStart or more
// than one.
std::vector<std::string> ExecStartFor(const std::filesystem::path& unit_file, std::string_view instance,
                                      const std::filesystem::path& bin_dir);

// The unit's Environment= assignments as (name, value) in order (later ones win when applied in order).
// Note for `cellctl up`: the units point CELL_DATA_DIR and CELL_CONFIG_DIR at /var/lib/cell and /etc/cell;
// a local cell keeps the caller's values for those instead.
std::vector<std::pair<std::string, std::string>> EnvironmentFor(const std::filesystem::path& unit_file,
                                                                std::string_view instance);

// One process of a cell, as `cellctl up` starts it.
struct UnitCommand {
  std::string unit;               // "cell-scheduler.service", "cell-interpreter@KT01.service"
  std::vector<std::string> argv;  // ExecStartFor(...)
};

// Whether a station's file has a table (`[serial]`): a template whose [Unit] has `X-CellStationTable=T`
// runs only for the stations with table T (cell-dnc@.service: the stations with a serial line).
using StationHasTable = std::function<bool(const std::string& station, const std::string& table)>;

// Every service of a cell from the units in `unit_dir` (e.g. <source>/deploy/systemd): each plain
// *.service once, then for each station in order each template *@.service; files in name order. A
// template with X-CellStationTable runs for the stations `has_table` says have it (none without it).
// Throws like ExecStartFor, and cell::Error(kNotFound) when unit_dir has no *.service.
std::vector<UnitCommand> CellCommands(const std::filesystem::path& unit_dir,
                                      const std::vector<std::string>& stations,
                                      const std::filesystem::path& bin_dir,
                                      const StationHasTable& has_table = {});

}  // namespace cell::config
