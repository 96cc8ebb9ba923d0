// What the program store knows about a file from its name and content alone: file type, dialect (declared
// or detected), the KT-APL FMS heading (NAM, UTL, UCY) with its placement rules, the program names inside
// Okuma / EMCO / Balt files, size and line count; plus the name rules of each dialect and the text check.
//
// The store's own small extractor (not the interpreter's parser): it reads only what the store, `program ls`
// and the scheduler need; the KT-APL heading comes from cell_ktapl_meta (cell/interp/ktapl_meta.h), the
// reader the interpreter and the scheduler use too. docs/program-store.md lists the rules and their sources.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cell::program_store {

enum class FileType {
  kPartProgram,  // a main program a station runs
  kLibrary,      // subroutines / cycles / subprograms (KT-APL DFS/DFC, Okuma .SUB/.SSB, EMCO M17 subroutines)
  kSchedule,     // Okuma schedule program (.SDF)
  kToolTable,    // tool data (KT-APL TLD statements, or the dialect's own form)
  kFixtureOffsets,  // KT-APL saved fixture offset table (NAME;FXT)
  kInspection,      // inspection file (KT-APL OIF output, CSV, QIF)
  kData,            // any other text file
};

enum class Dialect { kNone, kKtapl, kOkuma, kEmco, kBalt };

// Stable wire names: "part_program", "library", "schedule", "tool_table", "fixture_offsets", "inspection",
// "data"; dialects "ktapl", "okuma", "emco", "balt" and "" for none.
std::string_view FileTypeName(FileType type);
std::string_view DialectName(Dialect dialect);
// Accepts the wire names and a few aliases ("program", "sdf", "fxt", "tools", "lib", ...), case-insensitive.
// Throws cell::Error(kInvalidArgument) naming the accepted values.
FileType ParseFileType(std::string_view text);
// Accepts the wire names and aliases ("kt-apl", "kt", "osp", "emcotronic", "tm02", "balt-system", "none").
Dialect ParseDialect(std::string_view text);

// Throws cell::Error(kInvalidArgument) unless `content` is text: no NUL or other control bytes (tab, LF, CR,
// FF, VT and the DOS end-of-file ^Z are allowed) and valid UTF-8. The message gives the byte offset.
void CheckText(std::string_view content);

// Throws cell::Error(kInvalidArgument) with a one-line reason unless `name` is a legal name for a file of
// this type and dialect (empty, too long, illegal characters, bad extension). See docs/program-store.md.
void ValidateName(std::string_view name, FileType type, Dialect dialect);

// The file type a name implies by its extension, if any: ";FXT" fixture offsets, ".SDF" schedule, Okuma
// ".SUB"/".SSB"/".MSB"/".LIB" library, ".MIN" part program (case-insensitive).
std::optional<FileType> TypeFromName(std::string_view name);

struct Evidence {
  Dialect dialect = Dialect::kNone;
  int line = 0;         // 1-based
  std::string what;     // e.g. "(UTL,...) statement"
  bool strong = false;  // decisive on its own
};

struct Detection {
  Dialect dialect = Dialect::kNone;  // kNone when nothing or more than one dialect fits
  bool ambiguous = false;            // strong evidence for more than one dialect
  bool looks_like_nc = false;        // N/G/M blocks seen, whatever the dialect
  std::vector<Evidence> evidence;    // at most a few items per dialect
  // One line for the user: "ktapl ((UTL,...) statement, line 2)" or why no answer.
  std::string Explain() const;
};

// Scores the content against each dialect's distinctive forms.
Detection DetectDialect(std::string_view content);

struct Metadata {
  FileType type = FileType::kData;
  Dialect dialect = Dialect::kNone;
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
  // The dialect of the station whose namespace the file goes to (kNone for HOST). Used when detection finds
  // nothing dialect-specific in an NC program, or when the content fits several dialects and this is one of
  // them (with a warning). Never overrides a clear detection or a declaration.
  Dialect namespace_dialect = Dialect::kNone;
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
