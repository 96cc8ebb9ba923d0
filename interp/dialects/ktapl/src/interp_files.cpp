// Files a KT-APL program writes (manual ch. 7 ln 7886-8395, part 2 ch. 9): inspection files (G36 + OIF or
// MSG,NAM with the control's header; G37 / CLF), OPF/FWR/CLF data and NC files, and the file operations
// CPY, DLF, PRT, RCP, USF, ULF with their completion flags L1050-L1054.
//
// Every effect goes through Environment::FileOperation with the op as it is output (file_open, file_write,
// file_close, file_op): on a station that is the inspection writer and the program store, which answer once
// the operation is durable; the flag of an operation is set only then. A device error stops the run with
// the device's message unless CER covers its device class (MAS disk, SEQ printer, REM remote), in which
// case the run goes on with a warning message.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "interp_internal.h"

namespace cell::interp::ktapl {

namespace {

// The device class of a file operation (CER/SER, ln 8358-8395).
int DeviceOf(const std::string& what) {
  if (what == "PRT") return kDeviceSeq;
  if (what == "RCP") return kDeviceRem;
  return kDeviceMas;
}

}  // namespace

std::string InspectionHeader(const std::string& serial, const std::string& part_number,
                             const std::array<int, 6>& now) {
  // Ch. 7 ln 7898-7908: three entries, then the dashed delimiter (its length is lost in the scan).
  return fmt::format(
      "CONTROL SERIAL NUMBER = {}\nPALLET CODE/PART NUMBER = {}\n{:02d}:{:02d}:{:02d} {:02d}:{:02d}\n{}\n",
      serial, part_number, now[0] % 100, now[1], now[2], now[3], now[4], kInspectionDelimiter);
}

bool KtRun::FileDevice(const Canon& op, int device, int col) {
  FileResult r = env_->FileOperation(op);
  if (r.error.empty()) return r.done;
  if (cer_ & device) {
    // CER: the warning is displayed, no alarm, the program continues (ln 8364-8370).
    Out<MessageOp>().text = r.error;
    return false;
  }
  Fail(col, r.error);
}

void KtRun::OpenInspectionFile(std::string name, int col) {
  if (open_file_ == Upper(name)) return;  // the same file already open: ignored (ln 7894)
  OpenFile(name, "AS", false, col);
  FileOpenOp& c = Out<FileOpenOp>();
  c.name = name;
  c.type = "AS";
  c.inspection = true;
  Canon asked;
  asked.line = cur_line_;
  asked.p = c;
  FileDevice(asked, kDeviceMas, col);
  // The canned header, written when the file is first opened.
  auto number = [&](const char* param, double fallback) {
    std::optional<double> v = env_->SystemVariable(param);
    return fmt::format("{}", static_cast<long long>(std::trunc(v ? *v : fallback)));
  };
  std::string part = part_number_.empty() ? number("L3020", pallet_) : part_number_;
  std::string header = InspectionHeader(number("L3060", 0), part, env_->Now());
  for (size_t at = 0; at < header.size();) {
    size_t nl = header.find('\n', at);
    EmitFileWrite(header.substr(at, nl - at), col);
    at = nl + 1;
  }
}

void KtRun::CloseOpenFile(int col, bool flag) {
  if (open_file_.empty()) return;
  if (!fwr_pending_.empty()) {  // a ";" continuation with nothing after it still ends its line
    std::string rest = std::move(fwr_pending_);
    fwr_pending_.clear();
    EmitFileWrite(rest.substr(0, 80), col);
  }
  Out<FileCloseOp>();
  Canon asked;
  asked.line = cur_line_;
  asked.p = FileCloseOp{};
  open_file_.clear();
  if (FileDevice(asked, kDeviceMas, col) && flag) SetFlag(1050);
}

void KtRun::EmitFileWrite(std::string text, int col) {
  if (open_file_.empty()) return;
  files_[open_file_].text += text + "\n";
  FileWriteOp& w = Out<FileWriteOp>();
  w.text = std::move(text);
  Canon asked;
  asked.line = cur_line_;
  asked.p = w;
  FileDevice(asked, kDeviceMas, col);
}

void KtRun::StMsg(const Statement& st, BlockCtx&, bool) {
  const std::string& body = st.body;
  auto parts = SplitTopLevel(body, ',');
  if (parts.size() >= 2 && Upper(Trim(parts[0])) == "NAM") {
    if (!mode_.inspection_recording) Fail(st.col, "(MSG,NAM,...) NEEDS G36");
    std::string name = ExpandName(Trim(body.substr(parts[0].size() + 1)), st.col);
    if (name.empty() || name.size() > 32) Fail(st.col, "FILE NAME MUST HAVE 1-32 CHARACTERS");
    OpenInspectionFile(std::move(name), st.col);
    return;
  }
  std::string text = Trim(body);
  Out<MessageOp>().text = text;
  if (!open_file_.empty()) {
    // A message while a file is open is written to it, with an empty line after it (ln 8043-8097).
    EmitFileWrite(text.substr(0, 80), st.col);
    EmitFileWrite("", st.col);
  }
}

void KtRun::StOif(const Statement& st, BlockCtx&, bool) {
  if (!mode_.inspection_recording) Fail(st.col, "OIF NEEDS G36 IN THE BLOCK BEFORE");
  std::string name = ExpandName(Trim(st.body), st.col);
  if (name.empty() || name.size() > 32) Fail(st.col, "FILE NAME MUST HAVE 1-32 CHARACTERS");
  OpenInspectionFile(std::move(name), st.col);
}

void KtRun::StClf(const Statement& st, BlockCtx&, bool) {
  CloseOpenFile(st.col, true);
}

namespace {

// A fixture offset table file (USF/ULF, ;FXT): one FXC statement per line that is set, values in mm and
// degrees whatever the unit mode ("G71" first, so the file reads as what it is), I the B position G49
// selects the line at.
std::string FixtureFileText(const std::array<FixtureLine, kFixtureLines + 1>& lines) {
  std::string text = "G71\n";
  for (int h = 1; h <= kFixtureLines; ++h) {
    const FixtureLine& f = lines[static_cast<std::size_t>(h)];
    if (!f.set) continue;
    text += fmt::format("(FXC,H{}", h);
    for (int a : {kX, kY, kZ, kA, kB, kC}) text += fmt::format("{}{:.4f}", LetterOfAxis(a), f.v[a]);
    if (f.has_i) text += fmt::format("I{:.4f}", f.i);
    text += ")\n";
  }
  return text;
}

// Reads FixtureFileText's form back; false (the table untouched) when a line is not of it.
bool ParseFixtureFile(const std::string& text, std::array<FixtureLine, kFixtureLines + 1>& out) {
  std::array<FixtureLine, kFixtureLines + 1> lines{};
  std::size_t at = 0;
  while (at < text.size()) {
    std::size_t end = text.find('\n', at);
    if (end == std::string::npos) end = text.size();
    std::string line = Upper(Trim(text.substr(at, end - at)));
    at = end + 1;
    if (line.empty() || line == "G71") continue;
    if (line.rfind("(FXC,", 0) != 0 || line.back() != ')') return false;
    line = line.substr(5, line.size() - 6);
    int h = -1;
    std::size_t i = 0;
    while (i < line.size()) {
      const char letter = line[i++];
      const char* begin = line.c_str() + i;
      char* stop = nullptr;
      const double v = std::strtod(begin, &stop);
      if (stop == begin || !std::isfinite(v)) return false;
      i += static_cast<std::size_t>(stop - begin);
      if (letter == 'H') {
        if (v < 1 || v > kFixtureLines || v != std::floor(v)) return false;
        h = static_cast<int>(v);
        lines[static_cast<std::size_t>(h)].set = true;
      } else if (h < 0) {
        return false;
      } else if (letter == 'I') {
        lines[static_cast<std::size_t>(h)].has_i = true;
        lines[static_cast<std::size_t>(h)].i = v;
      } else {
        const int a = AxisOfLetter(letter);
        if (a < 0 || a > kC) return false;
        lines[static_cast<std::size_t>(h)].v[a] = v;
      }
    }
  }
  out = lines;
  return true;
}

}  // namespace

void KtRun::StFileOp(const Statement& st, BlockCtx&, bool) {
  const std::string& m = st.mnemonic;
  std::string args = st.body;
  std::string text;
  if (m == "USF" || m == "ULF") {
    std::string name = ExpandName(Trim(args), st.col);
    if (name.empty()) name = fmt::format("PALLET{:02d}", pallet_);
    if (name.size() > 28) Fail(st.col, "FIXTURE TABLE FILE NAME EXCEEDS 28 CHARACTERS");
    args = name + ";FXT";
    if (m == "USF") text = FixtureFileText(fixtures_);
  } else {
    auto parts = SplitTopLevel(args, ',', true);
    args.clear();
    for (size_t i = 0; i < parts.size(); ++i) {
      if (i) args += ',';
      args += ExpandName(Trim(parts[i]), st.col);
    }
  }
  FileOpOp& op = Out<FileOpOp>();
  op.what = m;
  op.args = args;
  op.text = text;
  Canon asked;  // the environment is asked about the same operation
  asked.line = cur_line_;
  asked.p = FileOpOp{m, args, text};
  if (!FileDevice(asked, DeviceOf(m), st.col)) return;
  if (m == "USF") files_[Upper(args)] = MemFile{"FXT", text};
  if (m == "ULF") LoadFixtureFile(args, st.col);
  if (m == "DLF") {
    files_.erase(Upper(Trim(SplitTopLevel(args, '/')[0])));
    SetFlag(1051);
  }
  if (m == "PRT") SetFlag(1052);
  if (m == "CPY") SetFlag(1053);
  if (m == "RCP") SetFlag(1054);
}

// ULF: the table saved by a USF of this run, else the file the control keeps (offline --lib DIR; on a
// station its namespace, then HOST, as programs are found). It replaces the whole fixture table.
void KtRun::LoadFixtureFile(const std::string& name, int col) {
  std::optional<std::string> text;
  if (auto it = files_.find(Upper(name)); it != files_.end()) {
    text = it->second.text;
  } else if (opt_.library) {
    text = opt_.library(name);
  }
  std::string error;
  if (!text) {
    error = "FILE " + name + " NOT FOUND";
  } else if (!ParseFixtureFile(*text, fixtures_)) {
    error = "FILE " + name + " IS NOT A FIXTURE OFFSET TABLE";
  }
  if (error.empty()) return;
  if (cer_ & kDeviceMas) {  // CER: a warning, the program goes on (ln 8364-8370)
    Out<MessageOp>().text = error;
    return;
  }
  Fail(col, error);
}

void KtRun::OpenFile(const std::string& name, const std::string& type, bool append, int col) {
  std::string key = Upper(name);
  CloseOpenFile(col, false);  // one open file at a time: the old one is closed first (ln 7894, 7924)
  auto it = files_.find(key);
  if (it != files_.end() && it->second.type != type) Fail(col, "FILE ALREADY EXISTS");
  const bool earlier = append && it == files_.end();
  MemFile& f = files_[key];
  f.type = type;
  if (!append) f.text.clear();
  // Appending to a file of an earlier run continues what the control keeps (offline: --lib; on a station:
  // its namespace), so that a CLS of it runs the whole file.
  if (earlier && opt_.library) {
    if (std::optional<std::string> text = opt_.library(name)) {
      f.text = std::move(*text);
      if (!f.text.empty() && f.text.back() != '\n') f.text += '\n';
    }
  }
  open_file_ = key;
}

void KtRun::StOpf(const Statement& st, BlockCtx&, bool) {
  auto parts = SplitTopLevel(st.body, ',', true);
  std::string name = Trim(parts[0]);
  std::string type = "AS";
  bool append = false;
  auto take_type = [&](std::string& s) {
    size_t slash = s.rfind('/');
    if (slash != std::string::npos && s.find('>', slash) == std::string::npos) {
      type = Upper(Trim(s.substr(slash + 1)));
      s = Trim(s.substr(0, slash));
    }
  };
  take_type(name);
  for (size_t i = 1; i < parts.size(); ++i) {
    std::string f = Upper(Trim(parts[i]));
    if (!f.empty() && f[0] == 'A' && (f.size() == 1 || f[1] == '/')) {
      append = true;
      if (f.size() > 1) type = Trim(f.substr(2));
    } else {
      type = f;
    }
  }
  if (type == "ASCII") type = "AS";
  if (type != "AS" && type != "NC") Fail(st.col, "ERROR - MUST BE EITHER NC prog OR ASCII");
  std::string file = ExpandName(name, st.col);
  if (file.empty() || file.size() > 32) Fail(st.col, "FILE NAME MUST HAVE 1-32 CHARACTERS");
  if (open_file_ == Upper(file)) return;  // already open and in use: ignored (ln 7924)
  OpenFile(file, type, append, st.col);
  FileOpenOp& c = Out<FileOpenOp>();
  c.name = std::move(file);
  c.type = type;
  c.append = append;
  Canon asked;
  asked.line = cur_line_;
  asked.p = c;
  FileDevice(asked, kDeviceMas, st.col);
}

void KtRun::StFwr(const Statement& st, BlockCtx&, bool) {
  if (open_file_.empty()) {
    if (cer_ & kDeviceMas) return;
    Fail(st.col, "PROCESS INSPECTION FILE NOT NAMED");
  }
  std::string body = st.body;
  bool cont = false;
  std::string tb = Trim(body);
  if (!tb.empty() && tb.back() == ';') {
    cont = true;
    tb.pop_back();
  }
  std::string line = fwr_pending_;
  // Fields: "text", Ln / LnI / LnR, or an axis letter; separated by commas (or simply adjacent).
  size_t i = 0;
  while (i < tb.size()) {
    char c = tb[i];
    if (c == ' ' || c == ',') {
      ++i;
      continue;
    }
    if (c == '"') {
      ++i;
      while (i < tb.size()) {
        if (tb[i] == '"') {
          if (i + 1 < tb.size() && tb[i + 1] == '"') {
            line += '"';
            i += 2;
            continue;
          }
          break;
        }
        line += tb[i++];
      }
      if (i >= tb.size()) Fail(st.col, "MISSING \" IN FWR TEXT");
      ++i;
      continue;
    }
    char u = Up(c);
    if (u == 'L' && i + 1 < tb.size() && (IsDigit(tb[i + 1]) || tb[i + 1] == '(')) {
      size_t j = i + 1;
      if (tb[j] == '(') {
        int depth = 0;
        for (; j < tb.size(); ++j) {
          if (tb[j] == '(') ++depth;
          if (tb[j] == ')' && --depth == 0) {
            ++j;
            break;
          }
        }
      } else {
        while (j < tb.size() && IsDigit(tb[j])) ++j;
      }
      int n = EvalParamRef(tb.substr(i, j - i), st.col);
      double v;
      try {
        v = Param(n);
      } catch (const ExprError& e) {
        Fail(st.col, e.text);
      }
      char mode = j < tb.size() ? Up(tb[j]) : 0;
      if (mode == 'I') {
        line += fmt::format("{}", static_cast<long long>(std::trunc(v)));
        ++j;
      } else if (mode == 'R') {
        line += fmt::format("{}", static_cast<long long>(std::floor(v + 0.5)));
        ++j;
      } else {
        line += FormatKtNumber(v);
      }
      i = j;
      continue;
    }
    if (AxisOfLetter(u) >= 0) {
      line += FormatKtNumber(Letter(u));
      ++i;
      continue;
    }
    Fail(st.col, "FWR FIELD MUST BE \"text\", A PARAMETER OR AN AXIS LETTER");
  }
  if (cont) {
    fwr_pending_ = line;
    return;
  }
  fwr_pending_.clear();
  EmitFileWrite(line.substr(0, 80), st.col);
}

}  // namespace cell::interp::ktapl
