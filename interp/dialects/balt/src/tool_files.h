// Balt-System's data files on memory MP3 as text: the offsets file FI1COR (§6.4.1, ln 8049-8434), the tool
// life file GE1TOL (§6.4.3 / §6.6, ln 8172-8226, 8436-8521) and the origins file FILEOR (ln 8116-8170,
// 8641-8747); the random tool file FI1RAN on MP0 (§6.7, ln 8523-8559). FI1COR is the dialect's tool-table
// form (cell-interp --tools, cellctl tools load); GE1TOL, FILEOR and FI1RAN are files a run reads by name
// (RunOptions::library: --lib offline, the station's program store).
#pragma once

#include <map>
#include <string>
#include <string_view>

#include "cell/interp/canon.h"
#include "cell/tooltable/tooltable.h"

namespace cell::interp::balt {

// A record that does not read: 1-based line and column, the FILMS4 code (71 ERROR IN RECORD FORMAT) and
// a reason.
struct FileError {
  int line = 1;
  int col = 1;
  int code = 71;
  std::string text;
};

// Offset records "n Z.. K.." (ln 8065-8077, 8305-8331): n the offset number (negative: values in the
// alternative unit), the length on the axis its letter names (Z, or X, Y for a length along them), K the
// diameter; optional current/maximum wear values c.. m.. c.. m.. are read and not kept. '%' tape
// delimiters, ';' comments, commas, "/" record separators and a "[TOOL COMP]" key prefix are accepted.
// Each record becomes the tool-table entry whose tool is the offset number ("12"). Throws FileError.
tooltable::ToolTable ParseOffsets(std::string_view text, const tooltable::ToolTable& base,
                                  bool metric_machine);
// The same records written back (what RQU / RQP leave in the file).
std::string FormatOffsets(const tooltable::ToolTable& table);

// One tool of the tool life file: VTU,tool,T<alternative>,[TOOL COMP]<offset>,t<max>,t<min>,t<left>,<status>
// (ln 8450-8475); times in minutes; status A broken, B usable (life), C usable (wear), D out of life, E / F
// on the spindle (were B / C).
struct ToolLife {
  int tool = 0;
  int alt_tool = 0;
  int alt_offset = 0;
  double max_min = 0, min_min = 0, left_min = 0;
  char status = 'B';
};

struct ToolLifeFile {
  std::map<int, ToolLife> tools;
  std::string Format() const;
};
// Throws FileError.
ToolLifeFile ParseToolLife(std::string_view text);

// The random tool file FI1RAN on MP0 (§6.7, ln 8523-8559): one 4-digit record per magazine pocket, in pocket
// order; "0001" a normal tool, "9003" a special tool (tool 3) on each of the 3 pockets it occupies, "0000" an
// empty pocket; what follows the digits (the manual's "-----") is a comment.
struct RandomToolFile {
  std::map<int, int> pocket;  // tool -> its (first) pocket, 1-based
  std::map<int, bool> special;
};
// Throws FileError (FILMS4 71) for a record that is not 4 digits, a tool in two places, or a special tool
// not on exactly 3 consecutive pockets.
RandomToolFile ParseRandomTools(std::string_view text);

// Origin records "n X.. Y.. Z.." (1-3 axes, ln 8116-8170; n 0-99, negative n: alternative unit), mm.
struct OriginRecord {
  AxisArray v{};
  std::uint32_t axes = 0;
};
using OriginFile = std::map<int, OriginRecord>;
// Throws FileError.
OriginFile ParseOrigins(std::string_view text, bool metric_machine);
std::string FormatOrigins(const OriginFile& file);

}  // namespace cell::interp::balt
