// KT-APL heading data (NAM, UTL, UCY) and the heading rules (see ktapl.h, docs/program-store.md).
#include "cell/interp/ktapl.h"

#include <fmt/format.h>

#include <algorithm>
#include <string>

#include "cell/interp/ktapl_statements.h"
#include "cell/interp/scan.h"

namespace cell::interp {

namespace {

using Kind = HeadingNotice::Kind;

using scan::AllDigits;
using scan::IsDigit;

bool IsAlnum(char c) {
  return IsDigit(c) || (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
}

// 1-based column where `part` (a view into `line`) starts.
int ColumnOf(std::string_view line, std::string_view part) {
  return static_cast<int>(part.data() - line.data()) + 1;
}

// A NAM, UTL or UCY statement of a block.
struct HeadingStatement {
  std::string mnemonic;
  int col = 0;            // of the control-out character
  char close = ')';       // the control-in character it needs
  bool unclosed = false;  // the block ends before `close`
  bool comma = false;     // "MNE," (else the value is missing)
  std::string_view body;  // after the comma, up to `close`
};

class Reader {
 public:
  explicit Reader(const HeadingOptions& options) : options_(options) {}

  void Block(int ln, std::string_view line) {
    std::string_view t = ktapl::TrimView(line);
    if (t.empty() || t[0] == '!') return;  // blank and comment lines do not break the heading
    if (t == "%") {
      if (first_) percent_first_ = true;
      first_ = false;
      previous_ = Item::kPercent;
      return;
    }
    first_ = false;
    std::string_view s = t;
    if (s[0] == '/') s = ktapl::TrimView(s.substr(1));
    const bool numbered = s.size() >= 2 && (s[0] == 'N' || s[0] == 'n') && IsDigit(s[1]);

    std::string error;
    size_t error_at = line.size();
    bool heading = false;
    for (const ktapl::Statement& st : ktapl::FindStatements(line, &error, &error_at)) {
      if (!IsHeading(st.mnemonic)) continue;
      HeadingStatement h;
      h.mnemonic = st.mnemonic;
      h.col = st.col;
      h.close = line[static_cast<size_t>(st.col - 1)] == '(' ? ')' : '%';
      h.comma = st.has_body;
      h.body = line.substr(st.end - 1 - st.body.size(), st.body.size());
      if (!Readable(ln, h, line)) continue;  // not read, and not a heading statement for the order
      Read(ln, numbered, line, h);
      heading = true;
    }
    if (!error.empty() && error_at < line.size()) {  // a statement without its control-in character
      std::string_view rest = line.substr(error_at + 1);
      size_t k = 0;
      while (k < rest.size() && rest[k] == ' ') ++k;
      std::string mnemonic = ktapl::Upper(rest.substr(k, 3));
      if (IsHeading(mnemonic)) {
        HeadingStatement h;
        h.mnemonic = mnemonic;
        h.col = static_cast<int>(error_at) + 1;
        h.close = line[error_at] == '(' ? ')' : '%';
        h.unclosed = true;
        Readable(ln, h, line);
      }
    }
    if (!heading) previous_ = Item::kOther;
    if (numbered) numbered_seen_ = true;
  }

  Heading Finish() {
    if ((first_utl_line_ != 0 || ucy_line_ != 0) && !percent_first_) {
      Warn(Kind::kOrder, "", 0, 0,
           "the FMS heading must start with a % line (rewind stop) before NAM, UTL and UCY");
    }
    if (options_.part_program && first_utl_line_ != 0 && ucy_line_ == 0) {
      Warn(Kind::kOrder, "UCY", first_utl_line_, first_utl_col_,
           "(UTL,...) without (UCY,...): KT/FMS part programs need a cycle time right after the tool list");
    }
    return std::move(md_);
  }

 private:
  enum class Item { kNone, kPercent, kNam, kUtl, kUcy, kOther };

  static bool IsHeading(std::string_view mnemonic) {
    return mnemonic == "NAM" || mnemonic == "UTL" || mnemonic == "UCY";
  }

  void Warn(Kind kind, std::string mnemonic, int line, int column, std::string text) {
    md_.notices.push_back({kind, std::move(mnemonic), line, column, std::move(text)});
  }

  // The statement's form: false (with a warning) when it has no ',' or no closing character. Such a
  // statement is not read at all: it neither counts as the first NAM/UTL/UCY nor takes a place in the order.
  bool Readable(int ln, const HeadingStatement& h, std::string_view line) {
    if (h.unclosed) {
      Warn(Kind::kValue, h.mnemonic, ln, h.col,
           fmt::format("({},...) without closing '{}'", h.mnemonic, h.close));
      return false;
    }
    if (!h.comma) {
      Warn(Kind::kValue, h.mnemonic, ln, ColumnOf(line, h.body),
           fmt::format("expected ',' after {}", h.mnemonic));
      return false;
    }
    return true;
  }

  void Read(int ln, bool numbered, std::string_view line, const HeadingStatement& h) {
    if (h.mnemonic == "NAM") {
      Nam(ln, numbered, line, h);
      previous_ = Item::kNam;
    } else if (h.mnemonic == "UTL") {
      Utl(ln, line, h);
      previous_ = Item::kUtl;
    } else {
      Ucy(ln, line, h);
      previous_ = Item::kUcy;
    }
  }

  void Nam(int ln, bool numbered, std::string_view line, const HeadingStatement& h) {
    if (nam_line_ != 0) {
      Warn(Kind::kValue, "NAM", ln, h.col,
           fmt::format("second (NAM,...) ignored (first on line {})", nam_line_));
      return;
    }
    nam_line_ = ln;
    std::string_view name = ktapl::TrimView(h.body);
    const int col = ColumnOf(line, name);
    if (name.empty()) Warn(Kind::kValue, "NAM", ln, col, "(NAM,...) has an empty name");
    if (name.size() > 32) {
      Warn(Kind::kValue, "NAM", ln, col, fmt::format("NAM name '{}' is longer than 32 characters", name));
    }
    if (!std::all_of(name.begin(), name.end(), [](char c) { return IsAlnum(c) || c == ' '; })) {
      Warn(Kind::kValue, "NAM", ln, col,
           fmt::format("NAM name '{}' should have only letters, digits and spaces", name));
    }
    if (!name.empty()) md_.name = std::string(name);
    if (numbered) Warn(Kind::kOrder, "NAM", ln, h.col, "(NAM,...) carries no sequence number");
    if (numbered_seen_)
      Warn(Kind::kOrder, "NAM", ln, h.col, "(NAM,...) must come before the first numbered block");
  }

  void Utl(int ln, std::string_view line, const HeadingStatement& h) {
    if (first_utl_line_ == 0) {
      first_utl_line_ = ln;
      first_utl_col_ = h.col;
    }
    last_utl_line_ = ln;
    // The tool list may take several consecutive UTL blocks.
    if (previous_ != Item::kPercent && previous_ != Item::kNam && previous_ != Item::kUtl) {
      Warn(Kind::kOrder, "UTL", ln, h.col,
           "(UTL,...) must come right after % or (NAM,...) (FMS heading: %, NAM, UTL, UCY)");
    }
    const std::vector<std::string> entries = ktapl::SplitTopLevel(h.body, ',');
    size_t offset = 0;  // of the entry in the body
    bool any = false;
    for (size_t k = 0; k < entries.size(); ++k) {
      std::string_view raw = h.body.substr(offset, entries[k].size());
      offset += entries[k].size() + 1;
      std::string_view entry = ktapl::TrimView(raw);
      if (entry.empty() && k + 1 == entries.size() && !any) continue;  // "(UTL,)": nothing listed
      std::string_view digits = entry;
      if (!digits.empty() && (digits[0] == 'T' || digits[0] == 't')) digits.remove_prefix(1);
      if (!AllDigits(digits) || digits.size() > 7) {
        Warn(Kind::kValue, "UTL", ln, ColumnOf(line, entry),
             fmt::format("UTL entry '{}' is not a tool number (up to 7 digits, optionally prefixed with T)",
                         entry));
        continue;
      }
      md_.tools.emplace_back(digits);
      any = true;
    }
    if (!any) Warn(Kind::kValue, "UTL", ln, ColumnOf(line, h.body), "(UTL,...) lists no tools");
  }

  void Ucy(int ln, std::string_view line, const HeadingStatement& h) {
    if (ucy_line_ != 0) {
      Warn(Kind::kValue, "UCY", ln, h.col,
           fmt::format("second (UCY,...) ignored (first on line {})", ucy_line_));
      return;
    }
    ucy_line_ = ln;
    if (last_utl_line_ != 0 && previous_ != Item::kUtl) {
      Warn(Kind::kOrder, "UCY", ln, h.col,
           fmt::format("(UCY,...) must come directly after (UTL,...) (line {})", last_utl_line_));
    } else if (last_utl_line_ == 0 && previous_ != Item::kPercent && previous_ != Item::kNam) {
      Warn(Kind::kOrder, "UCY", ln, h.col,
           "(UCY,...) must come in the heading, after %, (NAM,...) and (UTL,...)");
    }
    std::string_view value = ktapl::TrimView(h.body);
    const int col = ColumnOf(line, value);
    const size_t dot = value.find('.');
    std::string_view whole = value.substr(0, dot);
    std::string_view frac = dot == std::string_view::npos ? std::string_view() : value.substr(dot + 1);
    if (!AllDigits(whole) || whole.size() > 7 || !(frac.empty() || AllDigits(frac))) {
      Warn(Kind::kValue, "UCY", ln, col,
           fmt::format("UCY value '{}' is not a cycle time in seconds (up to 7 digits)", value));
    } else if (options_.whole_seconds && dot != std::string_view::npos) {
      Warn(Kind::kValue, "UCY", ln, col,
           fmt::format("UCY value '{}' is not whole seconds (UCY,nnnnnnn)", value));
    } else {
      md_.cycle_s = std::stod(std::string(value));
    }
  }

  const HeadingOptions& options_;
  Heading md_;
  Item previous_ = Item::kNone;
  bool first_ = true, percent_first_ = false, numbered_seen_ = false;
  int nam_line_ = 0, first_utl_line_ = 0, first_utl_col_ = 0, last_utl_line_ = 0, ucy_line_ = 0;
};

}  // namespace

Heading ReadKtaplHeading(std::string_view text, const HeadingOptions& options) {
  Reader reader(options);
  int ln = 0;
  for (size_t start = 0; start <= text.size();) {
    size_t eol = text.find('\n', start);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view line = text.substr(start, eol - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    reader.Block(++ln, line);
    start = eol + 1;
  }
  return reader.Finish();
}

}  // namespace cell::interp
