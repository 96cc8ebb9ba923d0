#include "cell/scheduler/route.h"

#include <cctype>

#include "cell/error/error.h"
#include "cell/names/names.h"
#include "cell/names/program_ref.h"

namespace cell::scheduler {
namespace {

struct SpecError {
  std::size_t col;  // 0-based in the spec text
  std::string text;
};

// Splits a comma list with optional double quotes; offsets are relative to `text`, `base` is added.
std::vector<std::string> SplitList(std::string_view text, std::size_t base, const char* what) {
  std::vector<std::string> out;
  std::size_t i = 0;
  while (true) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    std::string item;
    const std::size_t item_col = base + i;
    if (i < text.size() && text[i] == '"') {
      const std::size_t close = text.find('"', i + 1);
      if (close == std::string_view::npos) throw SpecError{item_col, "unterminated quote"};
      item = std::string(text.substr(i + 1, close - i - 1));
      i = close + 1;
      while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
      if (i < text.size() && text[i] != ',') throw SpecError{base + i, "expected ',' after a quoted name"};
    } else {
      std::size_t comma = text.find(',', i);
      if (comma == std::string_view::npos) comma = text.size();
      std::size_t b = comma;
      while (b > i && (text[b - 1] == ' ' || text[b - 1] == '\t')) --b;
      item = std::string(text.substr(i, b - i));
      i = comma;
    }
    if (item.empty()) throw SpecError{item_col, std::string("empty ") + what + " name"};
    try {  // the names' own rules (docs/operations.md "Names"), before anything is sent or stored
      if (std::string_view(what) == "station")
        names::CheckStation(item, "station");
      else
        names::CheckProgramRef(item, "program");  // "BS01/MP2:P9": a program in a station's memory
    } catch (const Error& e) {
      throw SpecError{item_col, e.what()};
    }
    out.push_back(std::move(item));
    if (i >= text.size()) break;
    ++i;  // the comma
  }
  return out;
}

OpSpec ParseOp(std::string_view text) {
  // The first ':' outside quotes separates stations from programs.
  bool quoted = false;
  std::size_t colon = std::string_view::npos;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '"') quoted = !quoted;
    if (text[i] == ':' && !quoted) {
      colon = i;
      break;
    }
  }
  if (colon == std::string_view::npos) throw SpecError{0, "expected STATIONS:PROGRAMS"};
  OpSpec op;
  op.stations = SplitList(text.substr(0, colon), 0, "station");
  op.programs = SplitList(text.substr(colon + 1), colon + 1, "program");
  if (op.programs.size() > 75) throw SpecError{colon + 1, "more than 75 programs in one operation"};
  return op;
}

bool KeywordAt(std::string_view line, std::string_view kw) {
  if (line.size() < kw.size()) return false;
  for (std::size_t i = 0; i < kw.size(); ++i) {
    if (std::toupper(static_cast<unsigned char>(line[i])) != kw[i]) return false;
  }
  return line.size() == kw.size() || line[kw.size()] == ' ' || line[kw.size()] == '\t';
}

std::string Quote(const std::string& name) {
  const bool padded = !name.empty() && (name.front() == ' ' || name.back() == ' ');
  if (name.find_first_of(",:\"") == std::string::npos && !padded) return name;
  return "\"" + name + "\"";
}

}  // namespace

OpSpec ParseOpSpec(std::string_view text) {
  try {
    return ParseOp(text);
  } catch (const SpecError& e) {
    throw Error(Errc::kInvalidArgument,
                "--op " + names::Shown(text, 60) + ": column " + std::to_string(e.col + 1) + ": " + e.text);
  }
}

std::vector<RouteSpec> ParseRouteFile(std::string_view text, std::string_view source) {
  std::vector<RouteSpec> routes;
  int line_no = 0;
  std::size_t start = 0;
  auto fail = [&](std::size_t col, const std::string& what) {
    throw Error(Errc::kInvalidArgument, std::string(source) + ":" + std::to_string(line_no) + ":" +
                                            std::to_string(col) + ": error: " + what);
  };
  while (start <= text.size()) {
    std::size_t eol = text.find('\n', start);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view line = text.substr(start, eol - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    ++line_no;
    std::size_t indent = 0;
    while (indent < line.size() && (line[indent] == ' ' || line[indent] == '\t')) ++indent;
    std::string_view body = line.substr(indent);
    while (!body.empty() && (body.back() == ' ' || body.back() == '\t')) body.remove_suffix(1);
    if (!body.empty() && body.front() != '#') {
      if (KeywordAt(body, "ROUTE")) {
        std::string_view name = body.substr(5);
        while (!name.empty() && (name.front() == ' ' || name.front() == '\t')) name.remove_prefix(1);
        if (name.empty()) fail(indent + 1, "ROUTE needs a name");
        try {
          names::CheckRoute(name);
        } catch (const Error& e) {
          fail(indent + 7, e.what());
        }
        for (const auto& r : routes) {
          if (r.name == name) fail(indent + 7, "route '" + std::string(name) + "' defined twice");
        }
        routes.push_back(RouteSpec{std::string(name), {}});
      } else if (KeywordAt(body, "OP")) {
        if (routes.empty()) fail(indent + 1, "OP before any ROUTE");
        try {
          routes.back().ops.push_back(ParseOp(body.substr(3)));
        } catch (const SpecError& e) {
          fail(indent + 4 + e.col, e.text);
        }
      } else {
        fail(indent + 1, "expected ROUTE, OP or a # comment");
      }
    }
    if (eol == text.size()) break;
    start = eol + 1;
  }
  for (const auto& r : routes) {
    if (r.ops.empty()) {
      throw Error(Errc::kInvalidArgument, std::string(source) + ": error: route '" + r.name + "' has no OP");
    }
  }
  return routes;
}

std::string FormatRouteFile(const std::vector<RouteSpec>& routes) {
  std::string out;
  for (const auto& r : routes) {
    out += "ROUTE " + r.name + "\n";
    for (const auto& op : r.ops) {
      out += "OP ";
      for (std::size_t i = 0; i < op.stations.size(); ++i) out += (i ? "," : "") + Quote(op.stations[i]);
      out += " : ";
      for (std::size_t i = 0; i < op.programs.size(); ++i) out += (i ? "," : "") + Quote(op.programs[i]);
      out += "\n";
    }
  }
  return out;
}

}  // namespace cell::scheduler
