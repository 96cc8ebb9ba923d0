#include "cell/station/program_files.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <condition_variable>
#include <mutex>
#include <vector>

#include "cell/error/error.h"
#include "cell/station/station.h"

namespace cell::station {

namespace {

std::string Upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

std::string Trim(const std::string& s) {
  size_t a = s.find_first_not_of(' ');
  size_t b = s.find_last_not_of(' ');
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

std::vector<std::string> SplitCommas(const std::string& s) {
  std::vector<std::string> out;
  size_t at = 0;
  for (;;) {
    size_t c = s.find(',', at);
    out.push_back(Trim(s.substr(at, c == std::string::npos ? std::string::npos : c - at)));
    if (c == std::string::npos) return out;
    at = c + 1;
  }
}

}  // namespace

ProgramFiles::ProgramFiles(std::string station, std::string dialect, std::int32_t dispatch_id, int program,
                           StationIo& io, Clock& clock, std::function<void()> checkpoint,
                           Clock::Duration writer_wait)
    : station_(std::move(station)),
      dialect_(std::move(dialect)),
      dispatch_id_(dispatch_id),
      program_(program),
      io_(io),
      clock_(clock),
      checkpoint_(std::move(checkpoint)),
      writer_wait_(writer_wait) {}

interp::FileResult ProgramFiles::Apply(const interp::Canon& op) {
  if (const auto* o = std::get_if<interp::FileOpenOp>(&op.p)) {
    // Append (A/) continues the file: one this run closed, else the one the station's namespace keeps (an
    // earlier run's, or HOST's as programs are found), else a new one. Its close stores the whole text as the
    // next revision. A new name (or OIF's "opened a second time") starts empty.
    Closed start{"", o->inspection};
    if (o->append) {
      if (auto it = closed_.find(Upper(o->name)); it != closed_.end()) {
        start = it->second;
      } else {
        std::optional<std::string> earlier;
        interp::FileResult got = Patiently("program store", "FILE NOT OPENED", [&] {
          earlier = io_.Program(station_, o->name);
          return true;
        });
        if (!got.done) return got;
        if (earlier) start.text = std::move(*earlier);
        if (!start.text.empty() && start.text.back() != '\n') start.text += '\n';
      }
    }
    open_ = o->name;
    file_ = std::move(start);
    return {};
  }
  if (const auto* w = std::get_if<interp::FileWriteOp>(&op.p)) {
    if (!open_.empty()) file_.text += w->text + "\n";
    return {};
  }
  if (std::holds_alternative<interp::FileCloseOp>(op.p)) {
    // Nothing open here: its open failed (and CER let the program go on), so nothing is stored either.
    if (open_.empty()) return {false, "FILE NOT STORED: the file was not opened"};
    const std::string name = std::move(open_);
    open_.clear();
    closed_[Upper(name)] = file_;
    return Store(station_, name, file_);
  }
  if (const auto* f = std::get_if<interp::FileOpOp>(&op.p)) {
    if (f->what == "RCP") return RemoteCopy(f->args);
    if (f->what == "CPY") {
      // (CPY,file1,TO or FROM,file2): a local copy of a closed file (ln 8278-8314).
      auto a = SplitCommas(f->args);
      if (a.size() != 3) return {false, "TYPE II COMMAND SYNTAX ERROR"};
      const bool to = Upper(a[1]) == "TO";
      const std::string& src = to ? a[0] : a[2];
      const std::string& dst = to ? a[2] : a[0];
      auto it = closed_.find(Upper(src));
      if (it == closed_.end()) return {false, "SOURCE FILE READ ERROR"};
      closed_[Upper(dst)] = it->second;
      return Store(station_, dst, it->second);
    }
    if (f->what == "DLF") return Delete(Trim(f->args.substr(0, f->args.find('/'))));
    if (f->what == "USF") {
      // (USF[,name]): the fixture offset table as NAME;FXT in the station's namespace (ln 4253-4284), a new
      // revision over the last; the run's ULF reads it back as programs are found (namespace, then HOST).
      const std::string key = NextKey();
      return Patiently("program store", "FILE NOT STORED", [&] {
        io_.SaveFile(station_, f->args, f->text, StationIo::SaveAs{dialect_, "fixture_offsets", key});
        return true;
      });
    }
    if (f->what == "PRT") {
      // (PRT,filename): the print spool is a file of its own beside the original (ln 8191-8276).
      const std::string name = Trim(f->args);
      auto it = closed_.find(Upper(name));
      if (it == closed_.end()) return {false, "Error - PRT File Not Found or Not Closed"};
      return Store(station_, name + ".PRT", it->second);
    }
  }
  return {};
}

// The n-th store or delete of this program of the dispatch: a retry repeats the key, so neither the writer
// nor the store does it twice; two operations of one run (of one program or of two) never share it.
std::string ProgramFiles::NextKey() {
  return fmt::format("file-{}-{}-{}-{}", station_, dispatch_id_, program_, ++stores_);
}

interp::FileResult ProgramFiles::RemoteCopy(const std::string& args) {
  // (RCP,localfile,TO or FROM,node,remotefile/type) (ln 8316-8356).
  auto a = SplitCommas(args);
  if (a.size() != 4 || (Upper(a[1]) != "TO" && Upper(a[1]) != "FROM"))
    return {false, "TYPE II COMMAND SYNTAX ERROR"};
  if (Upper(a[1]) == "FROM")
    return {false, "ERROR - REMOTE FILE COPY ERROR 0001 (RCP FROM is not supported by this cell)"};
  auto it = closed_.find(Upper(a[0]));
  if (it == closed_.end()) return {false, "ERROR - REMOTE FILE COPY ERROR 0002 (" + a[0] + " not closed)"};
  std::string remote = a[3].substr(0, a[3].find('/'));
  if (remote.empty()) remote = a[0];
  return Store(Upper(a[2]), remote, it->second);
}

interp::FileResult ProgramFiles::Store(const std::string& node, const std::string& name, const Closed& file) {
  const std::string& text = file.text;
  if (text.size() > 65536) return {false, "FILE " + name + " LARGER THAN 64 KIB"};
  cell::InspectionRequest req;
  req.op(cell::INSPECTION_STORE_FILE);
  req.hdr().idempotency_key(NextKey());
  auto& f = req.file();
  f.file(name.substr(0, 64));
  f.station(node.substr(0, 16));
  f.dispatch_id(dispatch_id_);
  f.format(cell::INSPECTION_KT_TEXT);
  f.text(text);
  f.closed(true);
  f.time_ns(clock_.WallNs());
  StationIo::SaveAs as{dialect_, file.inspection ? "inspection" : "data",
                       req.hdr().idempotency_key().to_string()};
  // The writer's copy first, then the store's revision; a retry repeats neither (idempotency keys).
  interp::FileResult r =
      Patiently("inspection writer", "FILE NOT STORED", [&] { return io_.StoreRecord(req); });
  if (!r.done) return r;
  return Patiently("program store", "FILE NOT STORED", [&] {
    io_.SaveFile(node, name, text, as);
    return true;
  });
}

// (DLF,filename[/type]) deletes a file from the control directory, the station's namespace, programs
// included (ln 8006-8041). A file that is not there is already deleted (judgement call, ktapl.md); the
// writer's copy of an inspection file stays (it is the quality record).
interp::FileResult ProgramFiles::Delete(const std::string& name) {
  if (!open_.empty() && Upper(open_) == Upper(name))
    return {false, "FILE " + name + " IS OPEN: CLOSE IT BEFORE (DLF)"};
  closed_.erase(Upper(name));
  const std::string key = NextKey();
  bool existed = false;
  interp::FileResult r = Patiently("program store", "FILE NOT DELETED", [&] {
    existed = io_.DeleteFile(station_, name, key);
    return true;
  });
  if (r.done && !existed) spdlog::info("(DLF,{}): no such file in {}: nothing to delete", name, station_);
  return r;
}

// Waits for a writer or a store on the bus (a restart takes seconds); the run can be cancelled meanwhile.
// `attempt` returns false while the service is not there; an Error it throws is a refusal (the answer)
// unless the service went away mid-call.
interp::FileResult ProgramFiles::Patiently(const char* who, const char* failed,
                                           const std::function<bool()>& attempt) {
  std::mutex mu;
  std::condition_variable cv;
  const auto deadline = clock_.Now() + writer_wait_;
  for (;;) {
    checkpoint_();
    try {
      if (attempt()) return {};
    } catch (const Error& e) {
      if (e.code() != Errc::kTimeout && e.code() != Errc::kUnavailable)
        return {false, fmt::format("{}: {}: {}", failed, who, e.what())};
      spdlog::warn("{}: {}", who, e.what());
    }
    if (clock_.Now() >= deadline) return {false, fmt::format("{}: no {} on the bus", failed, who)};
    std::unique_lock lk(mu);
    clock_.Wait(lk, cv, std::chrono::milliseconds(200));
  }
}

}  // namespace cell::station
