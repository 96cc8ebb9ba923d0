// Okuma tool data: the cell's tool table entries by offset / nose-R number, and Okuma's text form of them.
#include "tool_data.h"

#include <fmt/format.h>

#include <cmath>
#include <string>

#include "block.h"
#include "cell/error/error.h"
#include "cell/interp/scan.h"

namespace cell::interp::okuma {

const tooltable::ToolEntry* ToolData::Entry(int n) const {
  if (n <= 0) return nullptr;
  if (n != memo_n_) {
    const auto* e = table_.Find(std::to_string(n));
    memo_ = e ? std::optional<tooltable::ToolEntry>(*e) : std::nullopt;
    memo_n_ = n;
  }
  return memo_ ? &*memo_ : nullptr;
}

double ToolData::OffsetX(int n) const {
  const auto* e = Entry(n);
  return e ? e->x_offset : 0;
}
double ToolData::OffsetZ(int n) const {
  const auto* e = Entry(n);
  return e ? e->z_offset : 0;
}
double ToolData::NoseX(int n) const {
  auto it = nose_xz_.find(n);
  if (it != nose_xz_.end()) return it->second.first;
  const auto* e = Entry(n);
  return e ? e->nose_radius : 0;
}
double ToolData::NoseZ(int n) const {
  auto it = nose_xz_.find(n);
  if (it != nose_xz_.end()) return it->second.second;
  const auto* e = Entry(n);
  return e ? e->nose_radius : 0;
}
double ToolData::NoseRadius(int n) const {
  return std::max(std::fabs(NoseX(n)), std::fabs(NoseZ(n)));
}
int ToolData::Tip(int n) const {
  const auto* e = Entry(n);
  return e ? e->tip : 0;
}

const tooltable::ToolEntry& ToolData::Set(int n, char what, double v) {
  memo_n_ = 0;
  std::string key = std::to_string(n);
  if (!table_.Find(key)) {
    tooltable::ToolEntry e;
    e.tool = key;
    e.socket = n;
    table_.Upsert(e);
  }
  tooltable::ToolEntry e = *table_.Find(key);
  switch (what) {
    case 'x':
      e.x_offset = v;
      break;
    case 'z':
      e.z_offset = v;
      break;
    case 'X':
    case 'Z': {
      auto it = nose_xz_.find(n);
      std::pair<double, double> xz =
          it != nose_xz_.end() ? it->second : std::pair{e.nose_radius, e.nose_radius};
      (what == 'X' ? xz.first : xz.second) = v;
      nose_xz_[n] = xz;
      e.nose_radius = std::max(std::fabs(xz.first), std::fabs(xz.second));
      break;
    }
    case 'P':
      e.tip = static_cast<int>(v);
      break;
    default:
      break;
  }
  table_.Upsert(e);
  return *table_.Find(key);
}

namespace {

// Reads constants only (a tool table is data, not a program).
class ConstantsOnly : public VarReader {
 public:
  double Common(int, int col) override { Fail(col, "a tool table holds numbers only"); }
  double Local(uint64_t, int col) override { Fail(col, "a tool table holds numbers only"); }
  Value System(uint64_t name, const Value*, int col) override {
    if (UnpackName(name) == "VPAI") return {3.14159265358979323846, false};
    Fail(col, "a tool table holds numbers only");
  }
};

}  // namespace

tooltable::ToolTable ParseToolDataText(std::string_view text, std::string_view source,
                                       const tooltable::ToolTable& base) {
  ToolData data;
  data.Load(base);
  ConstantsOnly consts;
  int line_no = 0, found = 0;
  Block b;
  auto fail = [&](int col, const std::string& what) {
    throw Error(Errc::kInvalidArgument, fmt::format("{}:{}:{}: error: {}", source, line_no, col, what));
  };
  for (std::string_view raw : scan::Lines(text)) {
    ++line_no;
    std::string_view line = scan::Trim(raw);
    if (line.empty() || line == "%" || line[0] == '$') continue;
    b.Clear();
    try {
      ParseBlock(line, b);
      if (b.stmt == Stmt::kProgramName) continue;
      if (b.stmt != Stmt::kNone)
        fail(b.stmt_col, "a tool table holds only VTOFX/VTOFZ/VNSRX/VNSRZ/VNSRP settings");
      for (const Item& it : b.items) {
        if (!it.assign) {
          const Word& w = b.words[it.i];
          fail(w.col, fmt::format("word {} in a tool table (only VTOFX/VTOFZ/VNSRX/VNSRZ/VNSRP settings)",
                                  AddrName(w.addr)));
        }
        const Assign& a = b.assigns[it.i];
        std::string name = a.kind == VarKind::kSystem ? UnpackName(a.name) : "";
        char what = name == "VTOFX"   ? 'x'
                    : name == "VTOFZ" ? 'z'
                    : name == "VNSRX" ? 'X'
                    : name == "VNSRZ" ? 'Z'
                    : name == "VNSRP" ? 'P'
                                      : 0;
        if (what == 0 || a.index < 0 || a.is_string) {
          fail(a.col, "a tool table holds only VTOFX[n]/VTOFZ[n]/VNSRX[n]/VNSRZ[n]/VNSRP[n]=value settings");
        }
        double n = Evaluate(b.pool, a.index, consts).v;
        if (n < 1 || n > 96 || n != std::floor(n))
          fail(a.col, fmt::format("{}[{}]: numbers are 1-96", name, n));
        double v = Evaluate(b.pool, a.value, consts).v;
        if (what == 'P' && (v < 0 || v > 9 || v != std::floor(v))) {
          fail(a.col, "VNSRP (nose R pattern) is 0-9");
        }
        if (what != 'P' && std::fabs(v) > 999.999)
          fail(a.col, fmt::format("{} outside 0 to +-999.999", name));
        data.Set(static_cast<int>(n), what, v);
        ++found;
      }
    } catch (const RunError& e) {
      fail(e.col, e.text);
    }
  }
  if (found == 0) {
    throw Error(
        Errc::kInvalidArgument,
        fmt::format("{}: no tool data found (an Okuma tool table is a program of VTOFX[n]=, VTOFZ[n]=, "
                    "VNSRX[n]=, VNSRZ[n]=, VNSRP[n]= settings)",
                    source));
  }
  return data.table();
}

std::string ToolDataText(const tooltable::ToolTable& t) {
  std::string out;
  for (const auto& e : t.entries()) {
    out += fmt::format("VTOFX[{0}]={1} VTOFZ[{0}]={2} VNSRX[{0}]={3} VNSRZ[{0}]={3} VNSRP[{0}]={4}\n", e.tool,
                       e.x_offset, e.z_offset, e.nose_radius, e.tip);
  }
  return out;
}

}  // namespace cell::interp::okuma
