// cellctl pallet set|show|run, route define|show|operate, schedule run, tools load
#include <fstream>
#include <sstream>

#include "cell/config/config.h"
#include "cell/interp/interp.h"
#include "cell/interp/station_rules.h"
#include "cell/names/names.h"
#include "cell/names/program_ref.h"
#include "cell/program_store/metadata.h"
#include "cell/scheduler/route.h"
#include "cell/tooltable/tooltable.h"
#include "context.h"

namespace cellctl {

namespace {

void CheckPallet(int p) {
  if (p < 1 || p > 255) throw Exit{2, "pallet " + std::to_string(p) + " is outside 1-255"};
}

void CheckStation(const std::string& id) {
  cell::names::CheckStation(id);
  auto ids = cell::config::ListStations();
  if (std::find(ids.begin(), ids.end(), id) == ids.end()) throw Exit{1, "unknown station '" + id + "'"};
}

// A scheduler command; `verb` names it in the idempotency key, its arguments travel in the request.
cell::SchedulerRequest Req(cell::SchedulerOp op, Context& ctx, const std::string& verb) {
  cell::SchedulerRequest r;
  r.op(op);
  cell::names::Assign(r.hdr().idempotency_key(), ctx.IdempotencyKey(verb), "idempotency key");
  return r;
}

nlohmann::json Info(const cell::SchedulerReply& r) {
  std::string s = r.info().to_string();
  return s.empty() ? nlohmann::json::object() : nlohmann::json::parse(s);
}

// The options of every FMS verb: one invocation parses one verb.
struct Opts {
  int pallet = 0;
  std::vector<std::string> programs, ops;
  std::string station, name, file;
};
using OptsPtr = std::shared_ptr<Opts>;

void AddPalletVerbs(CLI::App& app, Context& ctx, const OptsPtr& o) {
  auto* pallet = app.add_subcommand("pallet", "pallet maps")->require_subcommand(1);
  ServicesOnly(pallet, ctx);
  auto* pset = pallet->add_subcommand("set", "map pallet P to an ordered list of 1-75 programs");
  pset->add_option("P", o->pallet)->required()->transform(Decimal());
  pset->add_option("PROG", o->programs)->required();
  pset->callback([o, &ctx] {
    CheckPallet(o->pallet);
    if (o->programs.size() > 75) throw Exit{2, "a pallet map holds at most 75 programs"};
    for (auto& p : o->programs) cell::names::CheckProgramRef(p);  // "BS01/MP2:P9": a memory's program
    auto r = Req(cell::SCHED_PALLET_SET, ctx, "pallet-set");
    r.pallet(o->pallet);
    for (auto& p : o->programs) cell::names::Append(r.args(), p, "program name");
    ctx.Scheduler(r);
  });
  auto* pshow = pallet->add_subcommand("show", "the programs mapped to pallet P");
  pshow->add_option("P", o->pallet)->required()->transform(Decimal());
  pshow->add_flag("--json", ctx.json);
  pshow->callback([o, &ctx] {
    CheckPallet(o->pallet);
    auto r = Req(cell::SCHED_PALLET_SHOW, ctx, "pallet-show");
    r.pallet(o->pallet);
    auto j = Info(ctx.Scheduler(r));
    if (ctx.json) return Print(ctx, j, {});
    for (auto& p : j["programs"]) std::cout << p.get<std::string>() << "\n";
  });
  auto* prun = pallet->add_subcommand("run", "run pallet P's map on one station; prints the job id");
  prun->add_option("P", o->pallet)->required()->transform(Decimal());
  prun->add_option("--station", o->station)->required();
  prun->callback([o, &ctx] {
    CheckPallet(o->pallet);
    CheckStation(o->station);
    auto r = Req(cell::SCHED_PALLET_RUN, ctx, "pallet-run");
    r.pallet(o->pallet);
    cell::names::Assign(r.station(), o->station, "station id");
    std::cout << ctx.Scheduler(r).job_id() << "\n";
  });
}

void AddRouteVerbs(CLI::App& app, Context& ctx, const OptsPtr& o) {
  auto* route = app.add_subcommand("route", "FMS routes")->require_subcommand(1);
  ServicesOnly(route, ctx);
  auto* rdef = route->add_subcommand("define", "define NAME from --op \"ST1,ST2:PROG1,PROG2\" (or --file)");
  rdef->add_option("NAME", o->name)->required();
  rdef->add_option("--op", o->ops, "an operation: eligible stations, then the programs it runs (USING)");
  rdef->add_option("--file", o->file, "a route file (docs/scheduler.md)");
  rdef->add_flag("--json", ctx.json);
  rdef->callback([o, &ctx] {
    if (o->ops.empty() && o->file.empty()) throw Exit{2, "route define needs --op or --file"};
    cell::names::CheckRoute(o->name);
    for (auto& op : o->ops) cell::scheduler::ParseOpSpec(op);  // station and program names, before sending
    auto r = Req(cell::SCHED_ROUTE_DEFINE, ctx, "route-define");
    cell::names::Assign(r.name(), o->name, "route name");
    for (auto& op : o->ops) cell::names::Append(r.args(), op, "--op");
    if (!o->file.empty()) {
      std::string text = ReadLocalFile(o->file, 65536, "a route file");
      cell::scheduler::ParseRouteFile(text, o->file);
      cell::names::Assign(r.text(), text, "route file");
    }
    auto j = Info(ctx.Scheduler(r));
    if (ctx.json) Print(ctx, j, {});
  });
  auto* rshow = route->add_subcommand("show", "a route's operations with their UTL tools and UCY seconds");
  rshow->add_option("NAME", o->name)->required();
  rshow->add_flag("--json", ctx.json);
  rshow->callback([o, &ctx] {
    cell::names::CheckRoute(o->name);
    auto r = Req(cell::SCHED_ROUTE_SHOW, ctx, "route-show");
    cell::names::Assign(r.name(), o->name, "route name");
    auto j = Info(ctx.Scheduler(r));
    if (ctx.json) return Print(ctx, j, {});
    std::cout << "route " << o->name << "\n";
    int i = 0;
    for (auto& op : j.value("ops", nlohmann::json::array()))
      std::cout << "  op " << ++i << ": stations " << op.value("stations", nlohmann::json::array()).dump()
                << " programs " << op.value("programs", nlohmann::json::array()).dump() << " ucy_s "
                << op.value("ucy_s", nlohmann::json::array()).dump() << " tools "
                << op.value("tools", nlohmann::json::array()).dump() << "\n";
  });
  auto* rop = route->add_subcommand("operate", "start pallet P on route NAME; prints the job id");
  rop->add_option("NAME", o->name)->required();
  rop->add_option("--pallet", o->pallet)->required()->transform(Decimal());
  rop->callback([o, &ctx] {
    CheckPallet(o->pallet);
    cell::names::CheckRoute(o->name);
    auto r = Req(cell::SCHED_ROUTE_OPERATE, ctx, "route-operate");
    cell::names::Assign(r.name(), o->name, "route name");
    r.pallet(o->pallet);
    std::cout << ctx.Scheduler(r).job_id() << "\n";
  });
}

void AddScheduleVerbs(CLI::App& app, Context& ctx, const OptsPtr& o) {
  auto* sched = app.add_subcommand("schedule", "Okuma schedule programs")->require_subcommand(1);
  ServicesOnly(sched, ctx);
  auto* srun = sched->add_subcommand("run", "run FILE (a local file, or a stored name) on a station");
  srun->add_option("FILE", o->file)->required();
  srun->add_option("--station", o->station)->required();
  srun->callback([o, &ctx] {
    CheckStation(o->station);
    auto r = Req(cell::SCHED_SCHEDULE_RUN, ctx, "schedule-run");
    cell::names::Assign(r.station(), o->station, "station id");
    std::error_code ec;
    if (std::filesystem::exists(o->file, ec)) {
      // DESIGN §6: a local file is stored first in the station's namespace (a new revision when the name is
      // there already), so the job's program can be shown and run again by name.
      std::string text = ReadLocalFile(o->file, 65536, "a schedule run");
      std::string name = std::filesystem::path(o->file).filename().string();
      cell::names::CheckProgram(name, "schedule name");
      cell::program_store::Client::PutOptions po;
      po.node = o->station;
      po.force = true;
      po.file_type = "schedule";
      po.idempotency_key = ctx.IdempotencyKey("schedule-put");
      PrintWarnings(ctx.Programs().Put(name, text, po));
      cell::names::Assign(r.text(), text, "schedule text");
      cell::names::Assign(r.name(), name, "schedule name");
    } else {
      cell::names::CheckProgram(o->file, "schedule name");
      cell::names::Assign(r.name(), o->file, "schedule name");
    }
    std::cout << ctx.Scheduler(r).job_id() << "\n";
  });
}

void AddToolsVerbs(CLI::App& app, Context& ctx, const OptsPtr& o) {
  auto* tools = app.add_subcommand("tools", "tool data")->require_subcommand(1);
  auto* load =
      tools->add_subcommand("load", "send the station's tool data file (its dialect's form) to station ID");
  load->add_option("ID", o->station)->required();
  load->add_option("FILE", o->file)->required();
  load->callback([o, &ctx] {
    CheckStation(o->station);
    cell::StationRequest req;
    req.op(cell::STATION_LOAD_TOOLS);
    std::string text = ReadLocalFile(o->file, 65536, "a tool load");
    // The station's own check, here first with the file's name: text only, in the station dialect's
    // tool-table form, with at least one entry (KT-APL: "no TLD statement found"). The base is the station
    // file's initial table (a process compensation needs its tool's data set first); the station checks
    // against its live one.
    try {
      cell::program_store::CheckText(text);
    } catch (const cell::Error& e) {
      throw Exit{1, o->file + ": " + e.what()};
    }
    try {
      const auto cfg = cell::interp::LoadStation(o->station);
      cell::interp::ParseStationTools(cfg, text, o->file, cell::tooltable::ToolTable(cfg.tools));
    } catch (const cell::Error& e) {
      throw Exit{1, e.what()};
    }
    cell::names::Assign(req.text(), text, "tool data");
    try {
      ctx.StationCommand(o->station, req);
    } catch (const cell::Error& e) {
      // The station reads the text as "tools"; the user's diagnostic names the file they gave.
      std::string what = e.what();
      if (what.rfind("tools:", 0) == 0) what = o->file + what.substr(5);
      throw cell::Error(e.code(), what);
    }
  });
}

}  // namespace

void AddFmsVerbs(CLI::App& app, Context& ctx) {
  auto o = std::make_shared<Opts>();
  AddPalletVerbs(app, ctx, o);
  AddRouteVerbs(app, ctx, o);
  AddScheduleVerbs(app, ctx, o);
  AddToolsVerbs(app, ctx, o);
}

}  // namespace cellctl
