// A dispatch's programs through the interpreter library, their motion to the servo, and what they leave in
// the CNC's memory.
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <optional>

#include "cell/error/error.h"
#include "cell/interp/interp.h"
#include "cell/interp/serial.h"
#include "cell/interp/station_rules.h"
#include "cell/names/names.h"
#include "cell/names/program_ref.h"
#include "cell/partmodel/part_model.h"
#include "cell/station/program_files.h"
#include "cell/station/station.h"
#include "cell/station/to_segment.h"

namespace cell::station {

struct Station::ActiveRun {
  Dispatch d;
  std::int64_t started_ns = 0;
  int programs_done = 0;
  std::string program;
};

// Queue busters answered by the machine: the run's Next() blocks here until the servo reports (a probe) or
// the inputs match (WAI).
class Station::RunEnvironment : public interp::Environment, public interp::SerialChannel {
 public:
  RunEnvironment(Station& station, SegmentStream& stream, double probe_feed, ProgramFiles& files)
      : station_(station), stream_(stream), probe_feed_(probe_feed), files_(files) {}
  void WaitInputs(const std::string& spec) override { station_.WaitInputs(spec); }
  // Okuma READ/WRITE: the station's [serial] line (docs/dnc.md "Okuma READ/WRITE").
  Result SerialRead() override { return station_.SerialRead(dispatch_id_); }
  Result SerialWrite(const std::string& record) override {
    return station_.SerialWrite(dispatch_id_, record);
  }
  interp::ProbeResult Probe(const interp::ProbeMove& m) override {
    cell::MotionSegment seg;
    for (size_t i = 0; i < m.to.size(); ++i) seg.target()[i] = m.to[i];
    seg.axis_mask(0x1ff);
    seg.exact_stop(true);
    seg.feed(m.feed > 0 ? m.feed : probe_feed_);
    seg.probe_break(!m.make);
    seg.probe_length(m.length);
    const cell::ProbeResult got = stream_.Probe(seg);
    interp::ProbeResult r;
    r.event = got.contact();
    r.already = got.already();
    for (size_t i = 0; i < r.at.size(); ++i) r.at[i] = got.position()[i];
    return r;
  }

  // G38: the servo checks the spindle tool against its tool model where the axes stand.
  bool CheckTool(int flutes) override {
    (void)flutes;  // the servo's model knows a tool whole or broken, not its edges
    cell::MotionSegment seg;
    seg.tool_check(true);
    seg.exact_stop(true);
    return stream_.Probe(seg).contact();
  }
  std::vector<tooltable::ToolWear> TakeToolWear() override { return stream_.TakeWear(); }
  // Balt-System '#': the block waits for the motion before it.
  void Synchronize() override { stream_.WaitDrained(); }

  // Every file the program writes leaves the run here, to the inspection writer (program_files.h).
  interp::FileResult FileOperation(const interp::Canon& op) override { return files_.Apply(op); }

  // What the machine reports by the dialect's own names, as the offline CLI reads them from --params: the
  // station config's [params] (KT-APL L3060, the control's serial number in the inspection-file header);
  // KT-APL L3020, the pallet on the station, from the dispatch.
  std::optional<double> SystemVariable(const std::string& name) override {
    if (name == "L3020") return pallet_;
    return interp::ParamNumber(station_.cfg_, name);
  }
  void SetPallet(int pallet) { pallet_ = pallet; }
  void SetDispatch(std::int32_t id) { dispatch_id_ = id; }

 private:
  Station& station_;
  SegmentStream& stream_;
  double probe_feed_;
  ProgramFiles& files_;
  int pallet_ = 0;
  std::int32_t dispatch_id_ = 0;
};

void Station::Execute(const Dispatch& d, std::int64_t started_ns) {
  ActiveRun run{d, started_ns, 0, ""};
  // The servo starts each run from the state a pallet arrives in, A and C at their zero among it
  // (Machine::ToArrival): the rotary axes unwrap from there.
  unwrap_ = RotaryUnwrap{};
  stream_.Begin(d.dispatch_id, [this, id = d.dispatch_id] { Checkpoint(id); });
  board_.RunStarted(d.pallet, d.dispatch_id);
  board_.Queued(db_.Count(RunState::kQueued));
  board_.Publish();  // ACTIVE with its pallet now, not only once the run has made progress
  spdlog::info("dispatch {}: pallet {} running {} program(s)", d.dispatch_id, d.pallet, d.programs.size());
  std::string reason;
  bool ok = true;
  try {
    if (!stream_.WaitForServo(options_.servo_wait))
      throw Error(Errc::kUnavailable, "no axis servo for station " + cfg_.id + " on the bus");
    // A store restarting (systemd brings it back in a second or two, longer on a loaded host) is waited for
    // here, before anything of the run has happened, rather than failing the pallet at its first fetch.
    if (!io_.WaitForProgramStore(options_.store_wait))
      throw Error(Errc::kUnavailable,
                  fmt::format("no program store on the bus for station {} (waited {} s)", cfg_.id,
                              std::chrono::duration_cast<std::chrono::seconds>(options_.store_wait).count()));
    const std::vector<bool> model = SendPartModel(d);
    for (int rep = 0; rep < d.repeat; ++rep) {
      for (std::size_t i = 0; i < d.programs.size(); ++i) {
        const std::string& name = d.programs[i];
        if (model[i]) {
          ++run.programs_done;  // handed to the servo: the map's later entries keep their indices
          continue;
        }
        run.program = name.substr(0, name.find(','));  // a schedule run's file, without PSELECT's operands
        PublishRun(run, cell::RUN_ACTIVE);
        RunProgram(run, name);
        PublishRun(run, cell::RUN_ACTIVE);  // a program finished: its UCY leaves the backlog
      }
    }
  } catch (const std::exception& e) {
    ok = false;
    reason = e.what();
  }
  RunProgress end;
  end.dispatch_id = d.dispatch_id;
  end.programs_done = run.programs_done;
  end.end = ok                            ? RunState::kCompleted
            : cancel_id_ == d.dispatch_id ? RunState::kCancelled
                                          : RunState::kFailed;
  end.reason = reason;
  end.machine_s = stream_.RunMachineSeconds();
  end.finished_ns = clock_.WallNs();
  end.record = RunRecord(d, cfg_.id, end, run.started_ns);
  db_.EndRun(end);
  if (ok) {
    spdlog::info("dispatch {} completed: {:.3f} machine seconds", d.dispatch_id, end.machine_s);
  } else {
    spdlog::error("dispatch {} {}: {}", d.dispatch_id, RunStateName(*end.end), reason);
  }
  board_.RunEnded(ok, db_.Count(RunState::kQueued));
  PublishRun(run,
             ok                                 ? cell::RUN_COMPLETED
             : *end.end == RunState::kCancelled ? cell::RUN_CANCELLED
                                                : cell::RUN_FAILED,
             reason);
  board_.Publish();
  FlushOutbox();
}

// A pallet map may name the pallet's part model among its programs (a file the store keeps as type
// part_model, scheduler.md "Part models"): the servo gets it as the workpiece of this run before the first
// segment, and probes it instead of the table pallet's model from the station file. Returns which entries
// are models (not run).
std::vector<bool> Station::SendPartModel(const Dispatch& d) {
  std::vector<bool> model(d.programs.size(), false);
  for (std::size_t i = 0; i < d.programs.size(); ++i) {
    const std::string& entry = d.programs[i];
    if (entry.find(',') != std::string::npos) continue;         // a schedule run's PSELECT: a program
    if (!names::SplitProgramRef(entry).node.empty()) continue;  // "BS01/MP2:P9": a memory's program
    std::optional<std::string> text = io_.PartModel(d.node, entry);
    if (!text) continue;
    partmodel::ParsePartModel(*text, entry);  // "NAME:LINE:COL: ..." fails the run before any motion
    cell::PartModel part;
    part.pallet(d.pallet);
    part.name(entry.substr(0, 128));
    part.text(*text);
    stream_.SendPart(std::move(part));
    spdlog::info("dispatch {}: pallet {} carries part model {}", d.dispatch_id, d.pallet, entry);
    model[i] = true;
  }
  return model;
}

// A map's entry (names/program_ref.h): "NODE:NAME" from NODE alone, which must be HOST or this station's own
// (the scheduler sends another station's memory to nobody else); a plain NAME from `node`, then HOST.
std::optional<std::string> Station::ReadProgram(const std::string& node, const std::string& entry) {
  const names::ProgramRef ref = names::SplitProgramRef(entry);
  if (ref.node.empty()) {
    auto text = io_.Program(node, entry);
    if (!text) throw Error(Errc::kNotFound, "program '" + entry + "' is not in " + node + " or HOST");
    return text;
  }
  const std::string owner = names::NodeStation(ref.node);
  if (!owner.empty() && owner != cfg_.id)
    throw Error(Errc::kFailedPrecondition,
                "program '" + entry + "' is in " + owner + "'s memory: " + cfg_.id + " cannot read it");
  auto text = io_.ProgramIn(ref.node, ref.name);
  if (!text) throw Error(Errc::kNotFound, "program '" + ref.name + "' is not in " + ref.node);
  return text;
}

// The text the run is about to run, for the cell's toolpath view (topics::kStationProgram): a viewer under
// DDS Security may not fetch it from the store. A program past the sample's bound goes without its text.
void Station::PublishProgram(const Dispatch& d, const std::string& name, const std::string& text) {
  cell::StationProgram p;
  p.station(cfg_.id);
  p.dispatch_id(d.dispatch_id);
  p.program(name.substr(0, 128));
  p.node(d.node.substr(0, 16));
  p.size(static_cast<uint32_t>(text.size()));
  if (text.size() <= p.text().max_size) p.text(text);
  io_.PublishProgram(p);
}

// One program of the dispatch. It starts from the CNC's memory as it stands; what it changed there (machine
// parameters, TLD, ZTB) is committed after its end (with the servo drained) and at its failure, in one
// transaction with the run's progress, so the next program starts from it and a kill -9 loses nothing that
// was committed.
void Station::RunProgram(ActiveRun& run, const std::string& entry) {
  // A schedule run names PSELECT's operands, "A.MIN,O100,S.SUB" (docs/scheduler.md §9): the file, the program
  // in it and the subprogram file, the dialect's PROGRAM and SUB_FILE.
  const std::size_t comma = entry.find(',');
  const std::string name = entry.substr(0, comma);
  auto text = ReadProgram(run.d.node, name);
  PublishProgram(run.d, name, *text);
  const MemorySnapshot start = memory_.Get();
  interp::RunOptions opt;
  opt.dialect = cfg_.dialect;
  opt.program_name = name;
  opt.program_text = std::move(*text);
  // "NAME/MPn" (a Balt-System CLS or data file naming its memory) is NAME in the station's memory namespace
  // "ID/MPn" (MP1: the station's own); other names are looked for in the station's namespace, then HOST.
  auto where = [node = run.d.node](const std::string& lib) {
    const std::size_t slash = lib.find('/');
    if (slash == std::string::npos) return std::make_pair(node, lib);
    const std::string memory = lib.substr(slash + 1);
    return std::make_pair(memory == "MP1" ? node : node + "/" + memory, lib.substr(0, slash));
  };
  opt.library = [this, where](const std::string& lib) {
    auto [ns, name] = where(lib);
    return io_.Program(ns, name);
  };
  // Files saved into a named memory (Balt-System FILEOR/MP3, GE1TOL/MP3) go back to the store at once.
  opt.save = [this, where](const std::string& lib, const std::string& text) {
    if (lib.find('/') == std::string::npos) return;  // KT-APL SAVE: not kept by a station (as before)
    auto [ns, name] = where(lib);
    io_.SaveFile(ns, name, text, {});
  };
  opt.tools = start.image.tools;
  opt.variables = start.image.variables;
  // A pallet's first program starts from the state the pallet arrives in (Machine::ToArrival).
  if (run.programs_done == 0)
    if (const interp::Dialect* d = interp::FindDialect(cfg_.dialect)) d->PalletArrives(opt.variables);
  opt.params = cfg_.params;  // the station config's [params]: the dialect's machine settings (EMCO's monitor)
  opt.params["PALLET"] = std::to_string(run.d.pallet);
  // A coded-pallet module's TLD W is 1-127 (KT-APL ln 4081-4083; the dialect's CODED_PALLETS setting).
  if (cfg_.coded_pallets) opt.params["CODED_PALLETS"] = "1";
  opt.params["OPERATOR"] = "1";  // a station has an operator's cycle start: M99 M00 stops, as the manual says
  // The panel's [ENABLE OPTION STOP] switch, once the operator has set it, over the station file's default.
  if (const std::optional<bool> on = panel_.OptionalStop()) opt.params["OPTIONAL_STOP"] = *on ? "1" : "0";
  if (comma != std::string::npos) {
    const std::string rest = entry.substr(comma + 1);
    const std::size_t sub = rest.find(',');
    if (!rest.substr(0, sub).empty()) opt.params["PROGRAM"] = rest.substr(0, sub);
    if (sub != std::string::npos && sub + 1 < rest.size()) opt.params["SUB_FILE"] = rest.substr(sub + 1);
  }
  ProgramFiles files(
      cfg_.id, cfg_.dialect, run.d.dispatch_id, run.programs_done + 1, io_, clock_,
      [this, id = run.d.dispatch_id] { Checkpoint(id); }, options_.writer_wait);
  RunEnvironment env(*this, stream_, options_.probe_feed, files);
  env.SetPallet(run.d.pallet);
  env.SetDispatch(run.d.dispatch_id);
  AuxIo aux(cfg_.aux);  // interlocks ON and the spindle stopped: each program starts from the reset state
  opt.env = &env;
  auto program = interp::StartRun(opt);
  auto commit = [&] {
    RunProgress progress;
    progress.dispatch_id = run.d.dispatch_id;
    progress.programs_done = run.programs_done;
    // The cutting time the run has not charged itself (since its last tool change) goes with what it left.
    tooltable::ToolTable tools = program->Tools();
    for (const auto& w : stream_.TakeWear()) tools.Charge(w);
    memory_.Commit(start.image, tools, program->Variables(), progress);
  };
  try {
    auto last_status = clock_.Now();
    interp::Step s;
    for (;;) {
      Checkpoint(run.d.dispatch_id);
      program->NextInto(s);
      if (s.kind == interp::Step::kEnd) break;
      if (s.kind == interp::Step::kError) {
        board_.Warning(s.diag.alarm, s.diag.Format());
        throw Error(Errc::kInvalidArgument, s.diag.Format());
      }
      const interp::Canon& c = s.canon;
      const auto* change = c.If<interp::ToolChangeOp>();
      board_.Position(name, c.line, change ? &change->tool : nullptr);
      if (auto seg = ToSegment(c)) {
        unwrap_.Apply(c, *seg);
        stream_.Send(*seg);
      }
      ExecuteIo(name, c, aux);
      if (const auto* ev = c.If<interp::EventOp>()) {
        // KT-APL EVT: recorded for the supervisor (the manual's central computer): an event on the bus.
        cell::StationEvent e;
        e.station(cfg_.id);
        e.dispatch_id(run.d.dispatch_id);
        e.pallet(run.d.pallet);
        names::Assign(e.program(), name.substr(0, 64), "program name");
        e.line(c.line);
        e.text(ev->text.substr(0, 255));
        e.time_ns(clock_.WallNs());
        spdlog::info("{} line {}: event {}", name, c.line, ev->text);
        io_.PublishEvent(e);
      }
      if (const auto* m = c.If<interp::MessageOp>()) {
        spdlog::info("{} line {}: {}", name, c.line, m->text);
        board_.Message(m->text);
      }
      if (const auto* a = c.If<interp::AlarmOp>()) {
        // KT-APL M99: the alarm sounds and the message shows; the program goes on (an M00 in the block stops
        // it below). [ALARM RESET] (`cellctl station reset`) clears the condition.
        spdlog::warn("{} line {}: {}", name, c.line, a->text);
        board_.Warning("PROGRAM", a->text);
        board_.Publish();
      }
      if (const auto* stop = c.If<interp::StopOp>()) ProgramStop(name, c.line, *stop);
      if (clock_.Now() - last_status > options_.status_period) {
        board_.PublishChanged();
        last_status = clock_.Now();
      }
    }
    board_.PublishChanged();  // the program's last line, unless the last sample showed it
    stream_.WaitDrained();
    panel_.FixOverrides(false);  // the program's end resets its modes, M49 with them
  } catch (...) {
    panel_.FixOverrides(false);
    try {
      commit();  // what the program changed before it failed stays, as on the control
    } catch (const std::exception& e) {
      spdlog::error("dispatch {}: what {} changed could not be committed: {}", run.d.dispatch_id, name,
                    e.what());
    }
    throw;
  }
  ++run.programs_done;
  commit();
}

// M00, and M01 with the optional stop on: the block finishes (the motion before it drains), then the run
// waits for the operator's cycle start (`cellctl station start ID`) in PROGRAM_STOPPED / OPTIONAL_STOP, the
// pallet keeping its backlog; a cancel ends the wait (KT-APL ln 2485-2524).
void Station::ProgramStop(const std::string& program, int line, const interp::StopOp& stop) {
  stream_.WaitDrained();
  const std::uint64_t pressed = panel_.CycleStarts();
  const std::string what = !stop.why.empty() ? stop.why + ", cycle stop"
                           : stop.optional   ? "M01 optional stop"
                                             : "M00 program stop";
  std::string text = fmt::format("{} at {} line {}: press cycle start (cellctl station start {})", what,
                                 program, line, cfg_.id);
  if (const std::string msg = board_.LastMessage(); !msg.empty() && msg != stop.why) text += " - " + msg;
  if (!stop.why.empty()) board_.Warning("TOOL", stop.why);
  spdlog::info("{}", text);
  board_.Waiting(text, stop.optional ? cell::EXECUTION_OPTIONAL_STOP : cell::EXECUTION_PROGRAM_STOPPED);
  board_.Publish();
  try {
    stream_.WaitUntil([&] { return panel_.CycleStarts() > pressed; });
  } catch (...) {
    board_.Waiting("");
    throw;
  }
  spdlog::info("cycle start: {} goes on after line {}", program, line);
  board_.Waiting("");
  board_.Publish();
}

void Station::WaitInputs(const std::string& spec) {
  const auto want = ParseWaitSpec(spec);
  if (!want) {  // EMCO M65 and the like: no input model of theirs (docs/station.md, "Discrete I/O")
    spdlog::warn("input wait '{}' is not a discrete input the station models: not waited for", spec);
    return;
  }
  // The block goes active after the motion before it (read-ahead stops here), as SET's outputs do.
  stream_.WaitDrained();
  if (dio_.Satisfied(*want)) return;
  const std::string text = "waiting for " + Describe(*want);
  spdlog::info("{}", text);
  board_.Waiting(text);
  board_.Publish();
  try {
    stream_.WaitUntil([&] { return dio_.Satisfied(*want); });
  } catch (...) {
    board_.Waiting("");  // the run ends (cancel, stop, servo): no longer WAIT
    throw;
  }
  spdlog::info("inputs {} present: the run goes on", Describe(*want));
  board_.Waiting("");
  board_.Publish();
}

// Okuma READ/WRITE (ln 8075-8109) on the station's [serial] line, which its cell-dnc owns (docs/dnc.md "Okuma
// READ/WRITE"). A station without one refuses them with Alarm B, case 4, "RS232C is no longer in ready
// status" (ln 8103; docs/dialects/okuma.md judgement call): the program's data would go nowhere.
namespace {

std::string NoLine(const config::StationConfig& cfg, std::string_view what) {
  return fmt::format("{} on station {}: it has no serial line (no [serial] table in {}), RS232C not ready",
                     what, cfg.id, cfg.file.string());
}

}  // namespace

interp::SerialChannel::Result Station::SerialRead(std::int32_t dispatch_id) {
  if (!cfg_.serial) return {"", NoLine(cfg_, "READ")};
  stream_.WaitDrained();  // the block goes active after the motion before it
  const std::string holder = fmt::format("dispatch {}", dispatch_id);
  const std::string line = fmt::format("station {} line {}", cfg_.id, cfg_.serial->device);
  const std::string text = "READ: waiting for a record on " + cfg_.serial->device;
  spdlog::info("{}", text);
  board_.Waiting(text);
  board_.Publish();
  interp::SerialChannel::Result r;
  try {
    // Asked after at the stream's pace (200 ms): a stop, a reset or a cancel ends the wait (the run's
    // checkpoint throws), and cell-dnc ends a READ its station stopped asking after (kReadLease).
    stream_.WaitUntil([&] {
      try {
        std::optional<std::string> got = io_.LineRead(holder);
        if (!got) return false;
        r.record = std::move(*got);
      } catch (const Error& e) {
        r.error = fmt::format("{}: {}", line, e.what());
      }
      return true;
    });
  } catch (...) {
    board_.Waiting("");
    throw;
  }
  board_.Waiting("");
  board_.Publish();
  if (r.error.empty()) spdlog::info("READ: {} characters from {}", r.record.size(), cfg_.serial->device);
  return r;
}

interp::SerialChannel::Result Station::SerialWrite(std::int32_t dispatch_id, const std::string& record) {
  if (!cfg_.serial) return {"", NoLine(cfg_, "WRITE")};
  stream_.WaitDrained();
  Checkpoint(dispatch_id);
  try {
    io_.LineWrite(fmt::format("dispatch {}", dispatch_id), record);
  } catch (const Error& e) {
    return {"", fmt::format("station {} line {}: {}", cfg_.id, cfg_.serial->device, e.what())};
  }
  return {};
}

// Outputs change when their block goes active (KT-APL manual ln 3958-3959), so after the motion before it.
void Station::ExecuteIo(const std::string& program, const interp::Canon& c, AuxIo& aux) {
  // What the I/O model refuses stops the run like a program error, at the block that asked.
  auto checked = [&](auto&& f) {
    try {
      return f();
    } catch (const Error& e) {
      const std::string text = fmt::format("{}:{}: error: {}", program, c.line, e.what());
      board_.Warning("", text);
      throw Error(e.code(), text);
    }
  };
  if (const auto* sp = c.If<interp::SpindleOp>()) {
    // The work spindle's interlocks; a live tool is the servo's alone (a machine without one alarms there).
    if (sp->spindle == interp::SpindleId::kMain) aux.Spindle(*sp);
  } else if (const auto* o = c.If<interp::OutputOp>()) {
    const auto spec = checked([&] { return ParseOutputSpec(o->spec); });
    if (!spec) {
      // A signal the station does not model (Balt-System SA/SK buffers, H functions on a machine that has
      // no output for them) would be a program's effect dropped: the run stops at the block instead.
      checked([&]() -> void {
        throw Error(
            Errc::kFailedPrecondition,
            fmt::format("output '{}' is not a signal of station {} (its station file has no such output)",
                        o->spec, cfg_.id));
      });
    }
    stream_.WaitDrained();
    if (spec->save) {
      dio_.SavePowerUp();
    } else {
      checked([&] { dio_.SetOutputs(spec->bits); });
    }
  } else if (const auto* ovr = c.If<interp::OverridesOp>()) {
    // KT-APL M49/M48 (ln 2896-2937), Okuma M161/M160: from this block on; the motion before it runs at the
    // operator's setting.
    stream_.WaitDrained();
    panel_.FixOverrides(ovr->fixed);
  } else if (const auto* a = c.If<interp::AuxOp>()) {
    const auto bit = checked([&] { return aux.Aux(a->m); });
    if (!bit) return;
    stream_.WaitDrained();
    checked([&] { dio_.SetOutputs({*bit}); });
    spdlog::info("M{}: {}={}", a->m, bit->name, bit->value);
  }
}

void Station::PublishRun(const ActiveRun& run, cell::RunState state, const std::string& reason) {
  cell::RunStatus s;
  s.dispatch_id(run.d.dispatch_id);
  s.station(cfg_.id);
  s.job_id(run.d.job_id);
  s.pallet(run.d.pallet);
  s.state(state);
  names::Assign(s.program(), run.program, "program name");
  s.programs_done(run.programs_done);
  s.program_index(static_cast<int32_t>(
      run.d.programs.empty() ? 0 : run.programs_done % static_cast<int>(run.d.programs.size())));
  s.machine_s(stream_.RunMachineSeconds());
  s.started_ns(run.started_ns);
  if (state == cell::RUN_COMPLETED || state == cell::RUN_FAILED || state == cell::RUN_CANCELLED)
    s.finished_ns(clock_.WallNs());
  s.reason(reason.substr(0, 255));
  io_.PublishRun(s);
}

}  // namespace cell::station
