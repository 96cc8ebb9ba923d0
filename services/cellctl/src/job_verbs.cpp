// cellctl job ls|show|cancel|wait, inspect ls|cat|export
#include <algorithm>
#include <chrono>
#include <fstream>
#include <iostream>
#include <optional>
#include <thread>

#include "cell/bus/topics.h"
#include "cell/idl/inspection.h"
#include "cell/inspection/inspection_file.h"
#include "cell/names/names.h"
#include "cell/records/names.h"
#include "cell/records/page.h"
#include "context.h"

namespace cellctl {

namespace {

nlohmann::json JobInfo(Context& ctx, int id, bus::Millis timeout = bus::Millis(30000)) {
  cell::SchedulerRequest r;
  r.op(cell::SCHED_JOB_SHOW);
  r.job_id(id);
  try {
    return nlohmann::json::parse(ctx.Scheduler(r, timeout).info().to_string());
  } catch (const cell::Error& e) {
    if (e.code() == cell::Errc::kNotFound) throw Exit{2, e.what()};
    throw;
  }
}

}  // namespace

void AddJobVerbs(CLI::App& app, Context& ctx) {
  struct Opts {
    int id = 0;
    double timeout = -1;
    std::string name, pattern = "*", state, station;
  };
  auto o = std::make_shared<Opts>();
  auto* job =
      app.add_subcommand("job", "jobs: pallets on routes, pallet runs, schedule runs")->require_subcommand(1);
  ServicesOnly(job, ctx);

  auto* ls = job->add_subcommand("ls", "jobs by id");
  auto page = std::make_shared<Paging>();
  AddPaging(ls, *page, true);
  ls->add_option("--state", o->state, "only jobs in this state (QUEUED ... CANCELLED)")
      ->check(CLI::Validator(
          [](std::string& s) -> std::string {
            return cell::records::JobStateFromName(s) ? "" : "not a job state: " + cell::names::Shown(s);
          },
          "STATE"));
  ls->add_option("--station", o->station, "only jobs whose current or last visit is on this station");
  ls->add_flag("--json", ctx.json);
  ls->callback([o, page, &ctx] {
    if (!o->station.empty()) cell::names::CheckStation(o->station);
    cell::SchedulerRequest r;
    r.op(cell::SCHED_JOB_LIST);
    cell::names::Assign(r.station(), o->station, "station id");
    cell::names::Assign(r.state(), o->state, "job state");
    auto fetch = [&](const std::string& after, std::uint32_t want) {
      cell::names::Assign(r.page().after(), after, "--after");
      r.page().limit(want);
      cell::SchedulerReply rep = ctx.Scheduler(r);
      return cell::records::Page{nlohmann::json::parse(rep.info().to_string()), rep.more()};
    };
    Print(ctx, cell::records::CollectPages(page->limit, page->after, "id", fetch),
          {"id", "state", "route", "pallet", "station", "reason", "started", "finished", "cycle_s"});
  });

  auto* show = job->add_subcommand("show", "one job with its decision log");
  show->add_option("ID", o->id)->required()->transform(Decimal());
  show->add_flag("--json", ctx.json);
  show->callback([o, &ctx] {
    auto j = JobInfo(ctx, o->id);
    if (ctx.json) return Print(ctx, j, {});
    nlohmann::json flat = j;
    flat.erase("decisions");
    Print(ctx, flat, {});
    std::cout << "decisions:\n";
    for (auto& d : j.value("decisions", nlohmann::json::array())) std::cout << "  " << d.dump() << "\n";
  });

  auto* cancel = job->add_subcommand("cancel", "cancel a job");
  cancel->add_option("ID", o->id)->required()->transform(Decimal());
  cancel->callback([o, &ctx] {
    JobInfo(ctx, o->id);  // unknown id: exit 2
    cell::SchedulerRequest r;
    r.op(cell::SCHED_JOB_CANCEL);
    r.job_id(o->id);
    cell::names::Assign(r.hdr().idempotency_key(), ctx.IdempotencyKey("job-cancel"), "idempotency key");
    ctx.Scheduler(r);
  });

  auto* wait = job->add_subcommand("wait", "block until COMPLETED (exit 0), FAILED or CANCELLED (exit 1)");
  wait->add_option("ID", o->id)->required()->transform(Decimal());
  wait->add_option("--timeout", o->timeout, "wall seconds (exit 3 when reached)")->check(Real());
  wait->callback([o, &ctx] {
    auto start = std::chrono::steady_clock::now();
    auto left = [&]() -> bus::Millis {
      if (o->timeout < 0) return bus::Millis(1000);
      auto used = std::chrono::steady_clock::now() - start;
      return std::max(bus::Millis(0), std::chrono::duration_cast<bus::Millis>(
                                          std::chrono::duration<double>(o->timeout) - used));
    };
    // Follow the job's events; re-read `job show` now and then, so a missed event cannot hang us.
    bus::Reader<cell::JobStatus> events(ctx.Bus(), bus::topics::kJobStatus, bus::QosKind::kEvent);
    // With --timeout, a scheduler that is not there or does not answer (restarting: systemd brings it back in
    // seconds, and a newcomer on a loaded host can take longer than a call's 5 s to hear it) is asked again
    // until the timeout, which then ends the wait as any other (exit 3). A cell that is down is still said so
    // at once, and without --timeout the first failure ends the wait.
    std::string last_state = "unknown (no answer from the scheduler yet)";
    auto show = [&]() -> std::optional<nlohmann::json> {
      while (true) {
        try {
          return o->timeout < 0 ? JobInfo(ctx, o->id) : JobInfo(ctx, o->id, std::max(left(), bus::Millis(1)));
        } catch (const cell::Error& e) {
          const bool absent = e.code() == cell::Errc::kUnavailable || e.code() == cell::Errc::kTimeout;
          const bool cell_down = ctx.Bus().lone_means_down() && ctx.Bus().RemoteParticipants() == 0;
          if (!absent || cell_down || o->timeout < 0) throw;
          if (left().count() == 0) return std::nullopt;
          std::cerr << "cellctl: job wait: " << e.what() << ": asking again\n";
          std::this_thread::sleep_for(std::min(left(), bus::Millis(500)));
        }
      }
    };
    auto timed_out = [&] {
      std::cout << last_state << "\n";
      return Exit{3, "job " + std::to_string(o->id) + " still " + last_state + " after " +
                         std::to_string(o->timeout) + " s"};
    };
    while (true) {
      const auto j = show();
      if (!j) throw timed_out();
      std::string state = (*j)["state"].get<std::string>();
      last_state = state;
      if (cell::records::IsTerminalJobState(state)) {
        std::cout << state << "\n";
        if (state == "COMPLETED") return;
        throw Exit{1, "job " + std::to_string(o->id) + " " + state + ": " +
                          j->value("reason", nlohmann::json()).dump()};
      }
      if (o->timeout >= 0 && left().count() == 0) throw timed_out();
      events.WaitFor([&](const cell::JobStatus& s) { return s.job_id() == o->id; },
                     std::min(left(), bus::Millis(1000)));
    }
  });

  // DESIGN §6b: the projected schedule (docs/scheduler.md §15).
  auto* plan = app.add_subcommand("plan", "when each pallet is projected to start and end, on which station");
  plan->add_flag("--json", ctx.json);
  ServicesOnly(plan, ctx);
  plan->callback([&ctx] {
    cell::SchedulerRequest r;
    r.op(cell::SCHED_PLAN);
    const auto rows = nlohmann::json::parse(ctx.Scheduler(r).info().to_string());
    Print(ctx, rows, {"job", "pallet", "route", "op", "station", "start", "end", "waiting_for"});
  });
}

void AddInspectVerbs(CLI::App& app, Context& ctx) {
  auto name = std::make_shared<std::string>("*");
  auto* ins = app.add_subcommand("inspect", "run records and inspection files")->require_subcommand(1);
  ServicesOnly(ins, ctx);
  // A listing's station filter rides in the request's file record, which LIST leaves unused otherwise.
  auto ask = [&ctx](cell::InspectionOp op, const std::string& n, const cell::PageRequest& page,
                    const std::string& station = {}) {
    cell::InspectionRequest r;
    r.op(op);
    cell::names::CheckRecord(n);
    cell::names::Assign(r.name(), n, "record name");
    r.page(page);
    if (!station.empty()) cell::names::Assign(r.file().station(), station, "station id");
    return ctx.Inspection(r);
  };
  auto call = [ask](cell::InspectionOp op, const std::string& n) {
    return ask(op, n, {}).info().to_string();
  };
  auto* ls = ins->add_subcommand("ls", "records and files by name");
  ls->add_option("PATTERN", *name);
  auto station = std::make_shared<std::string>();
  ls->add_option("--station", *station, "only the run records and inspection files of station ID");
  auto page = std::make_shared<Paging>();
  AddPaging(ls, *page, false);
  ls->add_flag("--json", ctx.json);
  ls->callback([name, station, ask, page, &ctx] {
    if (!station->empty()) cell::names::CheckStation(*station);
    auto fetch = [&](const std::string& after, std::uint32_t want) {
      cell::PageRequest p;
      cell::names::Assign(p.after(), after, "--after");
      p.limit(want);
      auto rep = ask(cell::INSPECTION_LIST, *name, p, *station);
      return cell::records::Page{nlohmann::json::parse(rep.info().to_string()), rep.more()};
    };
    Print(ctx, cell::records::CollectPages(page->limit, page->after, "name", fetch),
          {"name", "station", "kind", "size"});
  });
  auto* cat = ins->add_subcommand("cat", "print one record or file");
  cat->add_option("NAME", *name)->required();
  cat->callback([name, call] { std::cout << call(cell::INSPECTION_CAT, *name); });

  struct ExportOpts {
    std::string format = "text", output, units = "inch";
  };
  auto e = std::make_shared<ExportOpts>();
  auto* exp = ins->add_subcommand("export", "a stored KT-APL inspection file as text, CSV or QIF 3.0");
  exp->add_option("NAME", *name, "as `inspect ls` names it, e.g. KT01/PUMP341")->required();
  exp->add_option("--format", e->format, "text (the file as the control writes it), csv or qif")
      ->check(CLI::IsMember({"text", "csv", "qif"}));
  exp->add_option("-o,--output", e->output, "write to FILE instead of stdout");
  // The file does not say its unit: positions are in the program's G70/G71 units, inch unless it said G71.
  exp->add_option("--units", e->units, "the program's linear unit: inch (default) or mm")
      ->check(CLI::IsMember({"inch", "mm"}));
  exp->callback([name, e, call] {
    namespace ins = cell::inspection;
    const std::string text = call(cell::INSPECTION_CAT, *name);
    ins::InspectionFile file;
    try {
      file = ins::Parse(text);
    } catch (const ins::ParseError& err) {
      throw Exit{1, *name + ":" + err.what()};
    }
    const auto unit = e->units == "mm" ? ins::LinearUnit::kMillimetre : ins::LinearUnit::kInch;
    const std::string out = e->format == "csv"   ? ins::ToCsv(file, unit)
                            : e->format == "qif" ? ins::ToQif(file, unit, *name)
                                                 : ins::Format(file);
    if (e->output.empty()) {
      std::cout << out;
      return;
    }
    std::ofstream f(e->output, std::ios::binary | std::ios::trunc);
    f << out;
    f.close();
    if (!f) throw Exit{1, "cannot write " + e->output};
  });
}

}  // namespace cellctl
