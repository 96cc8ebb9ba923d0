#include "cell/program_store/metadata.h"

#include <fmt/format.h>

#include <algorithm>
#include <map>

#include "cell/error/error.h"
#include "cell/interp/scan.h"
#include "cell/partmodel/part_model.h"

namespace cell::program_store {
namespace {

using namespace interp::scan;

[[noreturn]] void Invalid(const std::string& what) {
  throw cell::Error(Errc::kInvalidArgument, what);
}

bool In(std::string_view word, std::initializer_list<std::string_view> set) {
  return std::find(set.begin(), set.end(), word) != set.end();
}

bool HasKind(Dialect d, FileType type) {
  auto kinds = d->kinds();
  return std::find(kinds.begin(), kinds.end(), type) != kinds.end();
}

int Score(const std::vector<Evidence>& evidence, Dialect d) {
  int score = 0;
  for (const Evidence& e : evidence) {
    if (e.dialect == d) score += e.strong ? 10 : 2;
  }
  return score;
}

constexpr std::size_t kMaxGenericName = 128;  // the DDS bound of ProgramRequest.name

}  // namespace

// ---------------------------------------------------------------------------------------------------------
// Names of types and dialects

std::string_view FileTypeName(FileType type) {
  return interp::FileKindName(type);
}

std::string_view DialectName(Dialect dialect) {
  return dialect == nullptr ? std::string_view("")
                            : dialect->name();  // "" (not a null view): SQLite NOT NULL
}

FileType ParseFileType(std::string_view text) {
  std::string t = Upper(Trim(text));
  std::replace(t.begin(), t.end(), '-', '_');
  if (In(t, {"PART_PROGRAM", "PROGRAM", "PART", "MAIN", "MIN"})) return FileType::kPartProgram;
  if (In(t, {"LIBRARY", "LIB", "SUBROUTINE", "SUBPROGRAM", "CYCLE", "SUB"})) return FileType::kLibrary;
  if (In(t, {"SCHEDULE", "SCHEDULE_PROGRAM", "SDF"})) return FileType::kSchedule;
  if (In(t, {"TOOL_TABLE", "TOOLS", "TOOLTABLE"})) return FileType::kToolTable;
  if (In(t, {"FIXTURE_OFFSETS", "FIXTURE_OFFSET_TABLE", "FIXTURE", "FXT"})) return FileType::kFixtureOffsets;
  if (In(t, {"INSPECTION", "INSPECTION_FILE"})) return FileType::kInspection;
  if (In(t, {"DATA", "DATA_FILE", "TEXT"})) return FileType::kData;
  if (In(t, {"PART_MODEL", "MODEL", "WORKPIECE"})) return FileType::kPartModel;
  Invalid(
      fmt::format("unknown file type '{}' (use part_program, library, schedule, tool_table, "
                  "fixture_offsets, inspection, data or part_model)",
                  text));
}

Dialect ParseDialect(std::string_view text) {
  std::string t = Upper(Trim(text));
  if (In(t, {"", "NONE"})) return nullptr;
  if (Dialect d = interp::FindDialect(t)) return d;
  Invalid(fmt::format("unknown dialect '{}' (use {})", text.substr(0, 32), interp::DialectList()));
}

Dialect OwnerOf(FileType type) {
  Dialect owner = nullptr;
  for (Dialect d : interp::Dialects()) {
    if (!HasKind(d, type)) continue;
    if (owner != nullptr) return nullptr;  // more than one: nobody owns it
    owner = d;
  }
  return owner;
}

// ---------------------------------------------------------------------------------------------------------
// Text check

void CheckText(std::string_view content) {
  std::size_t i = 0;
  while (i < content.size()) {
    auto c = static_cast<unsigned char>(content[i]);
    if (c < 0x80) {
      bool allowed = c >= 0x20 ? c != 0x7f
                               : (c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v' || c == 0x1a);
      if (!allowed) {
        Invalid(fmt::format("content is not text: control byte 0x{:02x} at offset {}", c, i));
      }
      ++i;
      continue;
    }
    // UTF-8 multi-byte sequence.
    int len = (c & 0xe0) == 0xc0 ? 2 : (c & 0xf0) == 0xe0 ? 3 : (c & 0xf8) == 0xf0 ? 4 : 0;
    bool ok =
        len != 0 && i + static_cast<std::size_t>(len) <= content.size() && c != 0xc0 && c != 0xc1 && c < 0xf5;
    for (int k = 1; ok && k < len; ++k) {
      ok = (static_cast<unsigned char>(content[i + static_cast<std::size_t>(k)]) & 0xc0) == 0x80;
    }
    if (!ok) Invalid(fmt::format("content is not text: invalid UTF-8 byte 0x{:02x} at offset {}", c, i));
    i += static_cast<std::size_t>(len);
  }
}

// ---------------------------------------------------------------------------------------------------------
// Names

std::optional<FileType> TypeFromName(std::string_view name) {
  for (Dialect d : interp::Dialects()) {
    if (auto kind = d->KindFromName(name)) return kind;
  }
  return std::nullopt;
}

void ValidateName(std::string_view name, FileType type, Dialect dialect) {
  // A kind only one dialect has follows that dialect's rules (a ;FXT table is a KT-APL file name).
  if (Dialect owner = OwnerOf(type)) dialect = owner;
  if (dialect != nullptr) return dialect->CheckName(name, type);
  CheckNameCharacters(name, "file");
  if (name.size() > kMaxGenericName) {
    Invalid(fmt::format("file name is too long: {} characters, at most {}", name.size(), kMaxGenericName));
  }
}

// ---------------------------------------------------------------------------------------------------------
// Detection

std::string Detection::Explain() const {
  auto list = [&](Dialect d) {
    std::string s;
    int n = 0;
    for (const Evidence& e : evidence) {
      if (e.dialect != d || n >= 3) continue;
      s += fmt::format("{}{} on line {}", n == 0 ? "" : ", ", e.what, e.line);
      ++n;
    }
    return s;
  };
  std::string out;
  for (Dialect d : interp::Dialects()) {
    std::string items = list(d);
    if (items.empty()) continue;
    if (!out.empty()) out += "; ";
    out += fmt::format("{} ({})", DialectName(d), items);
  }
  return out.empty() ? "no dialect-specific statements found" : out;
}

Detection DetectDialect(std::string_view content) {
  // Dialect evidence is in the heading and the first blocks; reading the first 1 MiB keeps detection of a
  // 20 MB program cheap. Cut at a line boundary.
  constexpr std::size_t kWindow = 1u << 20;
  if (content.size() > kWindow) {
    std::size_t cut = content.rfind('\n', kWindow);
    content = content.substr(0, cut == std::string_view::npos ? kWindow : cut + 1);
  }
  Detection det;
  for (Dialect d : interp::Dialects()) {
    std::vector<interp::Evidence> found;
    d->FindEvidence(content, found);
    std::map<std::string, bool> seen;  // the first line of each kind of evidence
    for (auto& e : found) {
      if (!seen.emplace(e.what, true).second) continue;
      det.evidence.push_back({d, e.line, std::move(e.what), e.strong});
    }
  }
  // Whatever the dialect: numbered blocks or the common G and M words make it an NC program.
  for (std::string_view raw : Lines(content)) {
    std::string upper = Upper(Trim(raw));
    if (upper.empty()) continue;
    bool numbered = false;
    std::string_view body = SkipSequence(upper, &numbered);
    if (numbered || HasWord(body, "G01") || HasWord(body, "G00") || HasWord(body, "G1") ||
        HasWord(body, "G0") || HasWord(body, "G2") || HasWord(body, "G3") || HasWord(body, "G02") ||
        HasWord(body, "G03") || HasMCode(body, 30) || HasMCode(body, 2) || HasMCode(body, 6) ||
        HasMCode(body, 3)) {
      det.looks_like_nc = true;
      break;
    }
  }
  std::vector<std::pair<int, Dialect>> scores;
  for (Dialect d : interp::Dialects()) scores.emplace_back(Score(det.evidence, d), d);
  std::stable_sort(scores.begin(), scores.end(), [](auto& a, auto& b) { return a.first > b.first; });
  int top = scores[0].first, second = scores.size() > 1 ? scores[1].first : 0;
  if (top >= 10 && second >= 10) {
    det.ambiguous = true;
  } else if ((top >= 10) || (top >= 2 && second == 0)) {
    det.dialect = scores[0].second;
  } else if (top > 0) {
    det.ambiguous = true;  // only weak hints for more than one dialect
  }
  if (det.dialect != nullptr || det.ambiguous) det.looks_like_nc = true;
  return det;
}

// ---------------------------------------------------------------------------------------------------------
// Extraction

std::uint64_t CountLines(std::string_view content) {
  if (content.empty()) return 0;
  auto n = static_cast<std::uint64_t>(std::count(content.begin(), content.end(), '\n'));
  return content.back() == '\n' ? n : n + 1;
}

namespace {

bool NeedsDialect(FileType type) {
  return type == FileType::kPartProgram || type == FileType::kLibrary || type == FileType::kSchedule;
}

}  // namespace

Metadata ExtractMetadata(std::string_view content, const ExtractOptions& options) {
  CheckText(content);
  Metadata md;
  md.size = content.size();
  md.lines = CountLines(content);

  std::optional<FileType> type = options.type;
  if (!type) type = TypeFromName(options.name);
  const std::string choices = interp::DialectChoices();
  if (Dialect owner = type ? OwnerOf(*type) : nullptr; owner != nullptr && !options.dialect) {
    md.dialect = owner;  // a kind only one dialect has: schedules are Okuma's, ;FXT tables KT-APL's
  } else if (options.dialect) {
    md.dialect = *options.dialect;
    if (md.dialect != nullptr) {
      Detection det = DetectDialect(content);
      if (det.dialect != nullptr && det.dialect != md.dialect && !det.ambiguous) {
        md.warnings.push_back(fmt::format("declared dialect {}, but the content looks like {}",
                                          DialectName(md.dialect), det.Explain()));
      }
    }
  } else if (!type || NeedsDialect(*type) || *type == FileType::kToolTable) {
    Detection det = DetectDialect(content);
    const Dialect station = options.namespace_dialect;
    bool station_has_evidence = std::any_of(det.evidence.begin(), det.evidence.end(),
                                            [&](const Evidence& e) { return e.dialect == station; });
    bool wants_dialect =
        det.looks_like_nc || (type && (NeedsDialect(*type) || *type == FileType::kToolTable));
    if (det.dialect != nullptr) {
      md.dialect = det.dialect;
      md.dialect_detected = true;
    } else if (det.ambiguous && station != nullptr && station_has_evidence) {
      md.dialect = station;
      md.dialect_detected = true;
      md.warnings.push_back(fmt::format(
          "the content fits more than one dialect ({}); took {}, the dialect of the station namespace",
          det.Explain(), DialectName(station)));
    } else if (det.ambiguous) {
      Invalid(fmt::format(
          "cannot tell the dialect: the content fits more than one: {}; declare it (--dialect {})",
          det.Explain(), choices));
    } else if (wants_dialect && station != nullptr) {
      md.dialect = station;  // nothing dialect-specific: the station's own dialect
      md.dialect_detected = true;
    } else if (wants_dialect) {
      Invalid(fmt::format(
          "cannot tell the dialect: {} (the content looks like an NC program but has no dialect-specific "
          "statement); declare it (--dialect {})",
          det.Explain(), choices));
    }
  }

  if (!type) type = md.dialect != nullptr ? md.dialect->Classify(content) : FileType::kData;
  md.type = *type;
  // A part model is read by the axis servo when a pallet map names it: a malformed one is refused here,
  // where its author is, not at the run.
  if (md.type == FileType::kPartModel) partmodel::ParsePartModel(content, options.name);
  if (NeedsDialect(md.type) && md.dialect == nullptr) {
    Invalid(fmt::format("a {} needs a dialect; declare it (--dialect {})", FileTypeName(md.type), choices));
  }
  if (md.dialect != nullptr && NeedsDialect(md.type) && !HasKind(md.dialect, md.type)) {
    Dialect owner = OwnerOf(md.type);
    Invalid(fmt::format("{} files are {} files, not {}", FileTypeName(md.type),
                        owner != nullptr ? std::string(owner->title()) : std::string("other dialects'"),
                        DialectName(md.dialect)));
  }

  if (md.dialect != nullptr) {
    interp::Heading heading =
        md.dialect->ReadHeading(content, {.part_program = md.type == FileType::kPartProgram});
    md.nam = heading.name.value_or("");
    md.utl = std::move(heading.tools);
    md.ucy_s = heading.cycle_s;
    md.program_names = std::move(heading.program_names);
    for (const interp::HeadingNotice& n : heading.notices) md.warnings.push_back(n.Format());
  }
  return md;
}

std::string DefaultName(std::string_view file_path, const Metadata& metadata) {
  if (!metadata.nam.empty()) return metadata.nam;
  std::size_t slash = file_path.find_last_of('/');
  return std::string(slash == std::string_view::npos ? file_path : file_path.substr(slash + 1));
}

}  // namespace cell::program_store
