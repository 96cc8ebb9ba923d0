// What the program store knows about a file from its name and content alone: file type, dialect (declared
// or detected), the dialect's heading (KT-APL NAM, UTL, UCY with their placement rules; the program names
// inside Okuma / EMCO / Balt files), size and line count; the name rules and the text check. The dialect
// knowledge comes from the registry (cell/interp/interp.h): the same readers the interpreter and the
// scheduler use. docs/program-store.md lists the rules and their sources.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cell/interp/interp.h"

namespace cell::program_store {

// A file's type is the registry's file kind; a dialect is a registry entry (nullptr: none). Every dialect
// rule (names, detection evidence, kinds, headings) comes from the dialect itself (cell/interp/interp.h).
using FileType = interp::FileKind;
using Dialect = const interp::Dialect*;

// Stable wire names: "part_program", "library", "schedule", "tool_table", "fixture_offsets", "inspection",
// "data"; dialects by their registry names and "" for none.
std::string_view FileTypeName(FileType type);
std::string_view DialectName(Dialect dialect);
// Accepts the wire names and a few aliases ("program", "sdf", "fxt", "tools", "lib", ...), case-insensitive.
// Throws cell::Error(kInvalidArgument) naming the accepted values.
FileType ParseFileType(std::string_view text);
// Accepts the registry's names and aliases ("kt-apl", "osp", "tm02", "balt-system", ...) and "" / "none"
// (nullptr). Throws cell::Error(kInvalidArgument) naming the dialects.
Dialect ParseDialect(std::string_view text);
// The one dialect that has a kind of file no other dialect has (schedules: Okuma; fixture offset tables:
// KT-APL), or nullptr.
Dialect OwnerOf(FileType type);

// Throws cell::Error(kInvalidArgument) unless `content` is text: no NUL or other control bytes (tab, LF, CR,
// FF, VT and the DOS end-of-file ^Z are allowed) and valid UTF-8. The message gives the byte offset.
void CheckText(std::string_view content);

// Throws cell::Error(kInvalidArgument) with a one-line reason unless `name` is a legal name for a file of
// this type and dialect (empty, too long, illegal characters, bad extension). See docs/program-store.md.
void ValidateName(std::string_view name, FileType type, Dialect dialect);

// The file type a name implies by a dialect's extension rule, if any: ";FXT" fixture offsets (KT-APL),
// ".SDF" schedule, ".SUB"/".SSB"/".MSB"/".LIB" library, ".MIN" part program (Okuma); case-insensitive.
std::optional<FileType> TypeFromName(std::string_view name);

struct Evidence {
  Dialect dialect = nullptr;
  int line = 0;         // 1-based
  std::string what;     // e.g. "(UTL,...) statement"
  bool strong = false;  // decisive on its own
};

struct Detection {
  Dialect dialect = nullptr;       // none when nothing or more than one dialect fits
  bool ambiguous = false;          // strong evidence for more than one dialect
  bool looks_like_nc = false;      // N/G/M blocks seen, whatever the dialect
  std::vector<Evidence> evidence;  // at most a few items per dialect
  // One line for the user: "ktapl ((UTL,...) statement, line 2)" or why no answer.
  std::string Explain() const;
};

// Scores the content against each dialect's distinctive forms.
Detection DetectDialect(std::string_view content);

struct Metadata {
  FileType type = FileType::kData;
  Dialect dialect = nullptr;
  bool dialect_detected = false;           // true when detected, false when declared (or none)
  std::string nam;                         // KT-APL (NAM,name), trimmed; "" when absent
  std::vector<std::string> utl;            // KT-APL (UTL,...) tool numbers, without the T prefix, as written
  std::optional<double> ucy_s;             // KT-APL (UCY,seconds)
  std::vector<std::string> program_names;  // Okuma O names, EMCO O numbers / %nn, Balt %:NAME
  std::uint64_t size = 0;                  // bytes
  std::uint64_t lines = 0;                 // lines (a last line without newline counts)
  std::vector<std::string> warnings;       // "line N: ..." placement and format problems
};

struct ExtractOptions {
  std::optional<Dialect> dialect;  // declared; detected when absent
  std::optional<FileType> type;    // declared; from name and content when absent
  std::string name;                // the name it is stored under (for TypeFromName)
  // The dialect of the station whose namespace the file goes to (none for HOST). Used when detection finds
  // nothing dialect-specific in an NC program, or when the content fits several dialects and this is one of
  // them (with a warning). Never overrides a clear detection or a declaration.
  Dialect namespace_dialect = nullptr;
};

// Checks the text, decides the type and dialect and extracts the metadata. Throws cell::Error
// (kInvalidArgument) for non-text content, or when the dialect is needed (an NC program) but cannot be
// told: ambiguous or unrecognised, with the evidence and the advice to declare it.
Metadata ExtractMetadata(std::string_view content, const ExtractOptions& options);

// Line count as the store reports it.
std::uint64_t CountLines(std::string_view content);

// A name for a file put without an explicit one: the KT-APL NAM when present, else the file's base name
// (directory removed). The caller still validates it.
std::string DefaultName(std::string_view file_path, const Metadata& metadata);

}  // namespace cell::program_store
