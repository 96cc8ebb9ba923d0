// cellctl pallet set|show|run, route define|show|operate, schedule run, tools load
#include <fstream>
#include <sstream>

#include "cell/config/config.h"
#include "context.h"

namespace cellctl {

namespace {

void CheckPallet(int p) {
  if (p < 1 || p > 255) throw Exit{2, "pallet " + std::to_string(p) + " is outside 1-255"};
}

void CheckStation(const std::string& id) {
  auto ids = cell::config::ListStations();
  if (std::find(ids.begin(), ids.end(), id) == ids.end()) throw Exit{1, "unknown station '" + id + "'"};
}

cell::SchedulerRequest Req(cell::SchedulerOp op, Context& ctx, const std::string& what) {
  cell::SchedulerRequest r;
  r.op(op);
  r.hdr().idempotency_key(ctx.IdempotencyKey(what));
  return r;
}

nlohmann::json Info(const cell::SchedulerReply& r) {
  std::string s = r.info().to_string();
  return s.empty() ? nlohmann::json::object() : nlohmann::json::parse(s);
}

}  // namespace

void AddFmsVerbs(CLI::App& app, Context& ctx) {
  struct Opts {
    int pallet = 0;
    std::vector<std::string> programs, ops;
    std::string station, name, file;
  };
  auto o = std::make_shared<Opts>();

  auto* pallet = app.add_subcommand("pallet", "pallet maps")->require_subcommand(1);
  auto* pset = pallet->add_subcommand("set", "map pallet P to an ordered list of 1-75 programs");
  pset->add_option("P", o->pallet)->required();
  pset->add_option("PROG", o->programs)->required();
  pset->callback([o, &ctx] {
    CheckPallet(o->pallet);
    if (o->programs.size() > 75) throw Exit{2, "a pallet map holds at most 75 programs"};
    auto r = Req(cell::SCHED_PALLET_SET, ctx, "pallet-set");
    r.pallet(o->pallet);
    for (auto& p : o->programs) r.args().push_back(p);
    ctx.Scheduler(r);
  });
  auto* pshow = pallet->add_subcommand("show", "the programs mapped to pallet P");
  pshow->add_option("P", o->pallet)->required();
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
  prun->add_option("P", o->pallet)->required();
  prun->add_option("--station", o->station)->required();
  prun->callback([o, &ctx] {
    CheckPallet(o->pallet);
    CheckStation(o->station);
    auto r = Req(cell::SCHED_PALLET_RUN, ctx, "pallet-run");
    r.pallet(o->pallet);
    r.station(o->station);
    std::cout << ctx.Scheduler(r).job_id() << "\n";
  });

  auto* route = app.add_subcommand("route", "FMS routes")->require_subcommand(1);
  auto* rdef = route->add_subcommand("define", "define NAME from --op \"ST1,ST2:PROG1,PROG2\" (or --file)");
  rdef->add_option("NAME", o->name)->required();
  rdef->add_option("--op", o->ops, "an operation: eligible stations, then the programs it runs (USING)");
  rdef->add_option("--file", o->file, "a route file (docs/scheduler.md)");
  rdef->add_flag("--json", ctx.json);
  rdef->callback([o, &ctx] {
    if (o->ops.empty() && o->file.empty()) throw Exit{2, "route define needs --op or --file"};
    auto r = Req(cell::SCHED_ROUTE_DEFINE, ctx, "route-define");
    r.name(o->name);
    for (auto& op : o->ops) r.args().push_back(op);
    if (!o->file.empty()) r.text(ReadLocalFile(o->file));
    auto j = Info(ctx.Scheduler(r));
    if (ctx.json) Print(ctx, j, {});
  });
  auto* rshow = route->add_subcommand("show", "a route's operations with their UTL tools and UCY seconds");
  rshow->add_option("NAME", o->name)->required();
  rshow->add_flag("--json", ctx.json);
  rshow->callback([o, &ctx] {
    auto r = Req(cell::SCHED_ROUTE_SHOW, ctx, "route-show");
    r.name(o->name);
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
  rop->add_option("--pallet", o->pallet)->required();
  rop->callback([o, &ctx] {
    CheckPallet(o->pallet);
    auto r = Req(cell::SCHED_ROUTE_OPERATE, ctx, "route-operate");
    r.name(o->name);
    r.pallet(o->pallet);
    std::cout << ctx.Scheduler(r).job_id() << "\n";
  });

  auto* sched = app.add_subcommand("schedule", "Okuma schedule programs")->require_subcommand(1);
  auto* srun = sched->add_subcommand("run", "run FILE (a local file, or a stored name) on a station");
  srun->add_option("FILE", o->file)->required();
  srun->add_option("--station", o->station)->required();
  srun->callback([o, &ctx] {
    CheckStation(o->station);
    auto r = Req(cell::SCHED_SCHEDULE_RUN, ctx, "schedule-run");
    r.station(o->station);
    std::ifstream probe(o->file);
    if (probe) {
      // DESIGN §6: a local file is stored first in the station's namespace (a new revision when the name is
      // there already), so the job's program can be shown and run again by name.
      std::string text = ReadLocalFile(o->file);
      std::string name = std::filesystem::path(o->file).filename().string();
      cell::program_store::Client::PutOptions po;
      po.node = o->station;
      po.force = true;
      po.file_type = "schedule";
      po.idempotency_key = ctx.IdempotencyKey("schedule-put:" + o->station + ":" + name);
      PrintWarnings(ctx.Programs().Put(name, text, po));
      r.text(text);
      r.name(name);
    } else {
      r.name(o->file);
    }
    std::cout << ctx.Scheduler(r).job_id() << "\n";
  });

  auto* tools = app.add_subcommand("tools", "tool data")->require_subcommand(1);
  auto* load =
      tools->add_subcommand("load", "send the station's tool data file (its dialect's form) to station ID");
  load->add_option("ID", o->station)->required();
  load->add_option("FILE", o->file)->required();
  load->callback([o, &ctx] {
    CheckStation(o->station);
    cell::StationRequest req;
    req.op(cell::STATION_LOAD_TOOLS);
    std::string text = ReadLocalFile(o->file);
    if (text.size() > 65536) throw Exit{1, o->file + " is larger than 64 KiB"};
    req.text(text);
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

}  // namespace cellctl
