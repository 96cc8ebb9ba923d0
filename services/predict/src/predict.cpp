#include "cell/predict/predict.h"

#include <fmt/format.h>

#include <chrono>
#include <cstdlib>
#include <memory>

#include "cell/error/error.h"
#include "cell/interp/interp.h"
#include "cell/interp/station_rules.h"
#include "cell/servo/machine.h"
#include "cell/servo/receiver.h"
#include "cell/station/io.h"
#include "cell/station/station.h"
#include "cell/station/to_segment.h"

namespace cell::predict {

namespace {

// Ends a prediction with a reason instead of a number (thrown from inside the run's Environment too).
struct NoNumber {
  std::string why;
  bool transient = false;  // Prediction::transient
};

// The station's servo model on the virtual clock, fed as the axis servo's receiver feeds it: on credit, with
// the whole queue as look-ahead (Receiver::LookAheadStarved keeps a virtual machine from starving while the
// producer sends), timed from the first kStarted to the last kCompleted (Receiver::HandleEvents).
class Sim {
 public:
  Sim(machine::MachineConfig cfg, const Input& in)
      : m_(std::move(cfg), servo::ClockKind::kVirtual),
        max_s_(in.max_machine_s),
        deadline_(std::chrono::steady_clock::now() +
                  std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                      std::chrono::duration<double>(in.max_wall_s))),
        stop_(in.stop) {}

  servo::Machine& machine() { return m_; }

  // One segment; waits for a credit as the station's stream does. Returns the probe result of a probe.
  void Push(servo::Segment s) {
    while (m_.credits() == 0)
      if (!Step()) throw NoNumber{"the servo model stopped with its queue full"};
    s.id = ++next_id_;
    try {
      m_.Push(s);
    } catch (const cell::Error& e) {
      throw NoNumber{fmt::format("the servo model refused a segment: {}", e.what())};
    }
    ++segments_;
  }
  void Push(const cell::MotionSegment& wire) { Push(servo::FromWire(wire, 0)); }

  // Everything sent so far completed: where the station waits (WaitDrained) the look-ahead ends there. Not
  // on to Idle (the axes settled to the micron): the station's virtual-clock servo lets no time pass once
  // every segment sent has completed, until the next one comes (Receiver::AwaitingProducer).
  void Drain() {
    Take();
    while (done_ < segments_ && Step()) {
    }
  }

  // A probe move or G38 check: sent, then waited for (SegmentStream::Probe), so the path stops there too.
  servo::ProbeResult Probe(const cell::MotionSegment& wire) {
    Push(wire);
    want_probe_ = next_id_;
    Drain();
    return probe_;
  }

  std::optional<double> Cycle() const {
    if (!first_) return std::nullopt;
    return last_ - *first_;
  }
  long segments() const { return segments_; }

  // The wall-clock bound and the caller's stop (checked every 1024 ticks: a clock read per tick costs).
  void CheckWall() const {
    if (std::chrono::steady_clock::now() > deadline_ || stop_.stop_requested())
      throw NoNumber{
          fmt::format("not predicted: still running at {:.0f} machine seconds {}", m_.machine_time(),
                      stop_.stop_requested() ? "when the prediction was stopped"
                                             : "after the prediction's wall-clock bound"),
          true};
  }

 private:
  bool Step() {
    if (!m_.Step()) return false;
    if (m_.HasEvents()) Take();
    if (m_.machine_time() > max_s_)
      throw NoNumber{fmt::format("did not end within {:.0f} machine seconds", max_s_)};
    if ((m_.ticks() & 0x3ff) == 0) CheckWall();
    return true;
  }
  void Take() {
    for (const servo::Event& e : m_.TakeEvents()) {
      if (e.kind == servo::EventKind::kStarted && !first_) first_ = e.machine_time;
      if (e.kind == servo::EventKind::kCompleted || e.kind == servo::EventKind::kFlushed) ++done_;
      if (e.kind == servo::EventKind::kCompleted) {
        last_ = e.machine_time;
        if (e.segment_id == want_probe_) probe_ = e.probe;
      }
      if (e.kind == servo::EventKind::kAlarm)
        throw NoNumber{
            fmt::format("the servo model raised alarm {}: {}", static_cast<int>(e.alarm.code), e.alarm.text)};
    }
  }

  servo::Machine m_;
  double max_s_;
  std::chrono::steady_clock::time_point deadline_;
  std::stop_token stop_;
  std::uint64_t next_id_ = 0, want_probe_ = 0;
  servo::ProbeResult probe_;
  std::optional<double> first_;
  double last_ = 0;
  long segments_ = 0, done_ = 0;  // pushed; completed or flushed
};

// What the station's RunEnvironment answers (services/interpreter/src/execute.cpp), on the model.
class Env : public interp::Environment {
 public:
  Env(Sim& sim, const Input& in, bool part) : sim_(sim), in_(in), part_(part) {}

  void WaitInputs(const std::string& spec) override {
    // A wait the station does not model (EMCO M65) is not waited for there either.
    if (!station::ParseWaitSpec(spec)) return;
    throw NoNumber{
        fmt::format("line {}: waits for inputs ({}): known only when the run has them", line_, spec)};
  }
  interp::ProbeResult Probe(const interp::ProbeMove& m) override {
    if (!part_)
      throw NoNumber{
          fmt::format("line {}: probes, and {} has no part model for {}: where the probe touches is "
                      "known only when the run has the part",
                      line_, in_.station.id,
                      in_.pallet ? fmt::format("pallet {}", in_.pallet) : std::string("an unknown pallet"))};
    cell::MotionSegment seg;
    for (size_t i = 0; i < m.to.size(); ++i) seg.target()[i] = m.to[i];
    seg.kind(cell::SEGMENT_PROBE);
    seg.axis_mask(0x1ff);
    seg.exact_stop(true);
    seg.feed(m.feed > 0 ? m.feed : station::StationOptions{}.probe_feed);
    seg.probe_break(!m.make);
    seg.probe_length(m.length);
    const servo::ProbeResult got = sim_.Probe(seg);
    interp::ProbeResult r;
    r.event = got.contact;
    r.already = got.already;
    for (int i = 0; i < servo::kNumAxes; ++i) r.at[static_cast<size_t>(i)] = got.position[i];
    return r;
  }
  bool CheckTool(int flutes) override {
    (void)flutes;
    cell::MotionSegment seg;
    seg.kind(cell::SEGMENT_PROBE);
    seg.tool_check(true);
    seg.exact_stop(true);
    return sim_.Probe(seg).contact;
  }
  void Synchronize() override { sim_.Drain(); }
  std::optional<double> SystemVariable(const std::string& name) override {
    if (name == "L3020" && in_.pallet) return in_.pallet;
    return interp::ParamNumber(in_.station, name);
  }
  void SetLine(int line) { line_ = line; }

 private:
  Sim& sim_;
  const Input& in_;
  bool part_;
  int line_ = 0;
};

// The station's RunOptions (Station::RunProgram) for one program.
interp::RunOptions Options(const Input& in, Env& env) {
  interp::RunOptions opt;
  opt.dialect = in.station.dialect;
  opt.program_name = in.program;
  opt.program_text = in.text;
  opt.library = in.library;
  opt.tools = in.tools ? *in.tools : tooltable::ToolTable(in.station.tools);
  opt.variables = in.variables;
  // The program is predicted as a pallet's first, from the state the pallet arrives in (as the station runs
  // it).
  if (const interp::Dialect* d = interp::FindDialect(in.station.dialect)) d->PalletArrives(opt.variables);
  opt.params = in.station.params;
  if (in.pallet) opt.params["PALLET"] = std::to_string(in.pallet);
  if (in.station.coded_pallets) opt.params["CODED_PALLETS"] = "1";
  opt.params["OPERATOR"] = "1";
  opt.env = &env;
  return opt;
}

// The station's I/O side of an op (Station::ExecuteIo): what it refuses stops the run, and an output or a
// mapped M code goes active after the motion before it.
void Io(const interp::Canon& c, station::AuxIo& aux, Sim& sim, const std::string& program) {
  try {
    if (const auto* sp = c.If<interp::SpindleOp>()) {
      // The work spindle's interlocks; a live tool is the servo model's alone, as on the station (a machine
      // without one raises the servo's alarm).
      if (sp->spindle == interp::SpindleId::kMain) aux.Spindle(*sp);
    } else if (const auto* o = c.If<interp::OutputOp>()) {
      if (station::ParseOutputSpec(o->spec)) sim.Drain();
    } else if (const auto* a = c.If<interp::AuxOp>()) {
      if (aux.Aux(a->m)) sim.Drain();
    } else if (c.If<interp::OverridesOp>()) {
      sim.Drain();  // KT-APL M48/M49, Okuma M160/M161: from this block on, the motion before it drained
    } else if (c.If<interp::StopOp>()) {
      sim.Drain();  // M00/M01: the operator's wait is not machine time on the virtual clock
    }
  } catch (const Error& e) {
    throw NoNumber{fmt::format("{}:{}: error: {}", program, c.line, e.what())};
  }
}

void RunProgram(const Input& in, Sim& sim, bool part) {
  Env env(sim, in, part);
  station::AuxIo aux(in.station.aux);
  auto run = interp::StartRun(Options(in, env));
  interp::Step s;
  station::RotaryUnwrap unwrap;  // A and C as the station sends them (to_segment.h)
  for (long ops = 0;; ++ops) {
    if (ops >= in.max_ops) throw NoNumber{fmt::format("did not end within {} operations", in.max_ops)};
    run->NextInto(s);
    if (s.kind == interp::Step::kEnd) break;
    if (s.kind == interp::Step::kError) throw NoNumber{s.diag.Format()};
    env.SetLine(s.canon.line);
    if (auto seg = station::ToSegment(s.canon)) {
      unwrap.Apply(s.canon, *seg);
      sim.Push(*seg);
    }
    Io(s.canon, aux, sim, in.program);
  }
  sim.Drain();
}

bool HasPart(const machine::MachineConfig& cfg, int pallet) {
  for (const auto& p : cfg.part_models)
    if (p.pallet == pallet) return true;
  return false;
}

}  // namespace

std::string DialectMismatch(const std::string& program_dialect, const config::StationConfig& station) {
  if (program_dialect.empty()) return "";
  const interp::Dialect* p = interp::FindDialect(program_dialect);
  const interp::Dialect* s = interp::FindDialect(station.dialect);
  if (!s) return fmt::format("{} runs '{}', a dialect this cell does not know", station.id, station.dialect);
  if (!p) return fmt::format("the program's dialect '{}' is not one this cell knows", program_dialect);
  if (p == s) return "";
  return fmt::format("{} runs {}, the program is {}: a station runs programs of its own dialect only",
                     station.id, s->name(), p->name());
}

Prediction Predict(const Input& in) {
  Prediction out;
  out.why = DialectMismatch(in.program_dialect, in.station);
  if (!out.why.empty()) return out;
  try {
    machine::MachineConfig cfg = in.machine ? *in.machine : machine::LoadMachineConfig(in.station.file);
    const bool part = in.pallet && HasPart(cfg, in.pallet);
    Sim sim(std::move(cfg), in);
    if (in.tools) sim.machine().SetToolTable(*in.tools);
    if (in.pallet) sim.machine().SetPallets(in.pallet, 0);
    RunProgram(in, sim, part);
    out.segments = sim.segments();
    out.seconds = sim.Cycle().value_or(0.0);
  } catch (const NoNumber& n) {
    out.why = n.why;
    out.transient = n.transient;
  } catch (const std::exception& e) {
    out.why = e.what();
  }
  return out;
}

}  // namespace cell::predict
