// cellctl program put|get|show|plot|rm|ls|cp|mv|protect|unprotect|import|export|memory
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>

#include "cell/config/config.h"
#include "cell/interp/interp.h"
#include "cell/interp/plot.h"
#include "cell/interp/station_rules.h"
#include "cell/machine/machine_config.h"
#include "cell/names/names.h"
#include "cell/program_store/client.h"
#include "cell/program_store/memory_commands.h"
#include "cell/program_store/metadata.h"
#include "cell/tooltable/wire.h"
#include "context.h"

namespace cellctl {

namespace {

void CheckAddress(const std::string& node, const std::string& name) {
  cell::names::CheckNode(node);
  cell::names::CheckProgram(name);
}

// The store's limit per file (StoreOptions::max_file_size): a larger file is refused from its size, before
// anything is read or streamed.
constexpr std::uint64_t kMaxProgramBytes = 256ull << 20;

std::string ReadProgram(const std::string& path) {
  return ReadLocalFile(path, kMaxProgramBytes, "the program store");
}

void WriteLocalFile(const std::string& path, const std::string& content) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << content;
  out.close();
  if (!out) throw cell::Error(cell::Errc::kIo, "cannot write " + path);
}

// The stored name: --name, else the KT-APL NAM, else the file's base name (DESIGN §6).
std::string NameFor(const std::string& path, const std::string& content, const std::string& dialect) {
  namespace ps = cell::program_store;
  ps::ExtractOptions o;
  if (!dialect.empty()) o.dialect = ps::ParseDialect(dialect);
  o.name = std::filesystem::path(path).filename().string();
  try {
    return ps::DefaultName(path, ps::ExtractMetadata(content, o));
  } catch (const cell::Error&) {
    return std::filesystem::path(path).filename().string();  // the store reports the real problem
  }
}

// The memory commands' store over the bus (one request per call; every mutating one keyed).
class ClientMemory : public cell::program_store::MemoryBackend {
 public:
  explicit ClientMemory(Context& ctx) : ctx_(ctx) {}
  std::vector<Entry> List(const std::string& node, const std::string& pattern) override {
    std::vector<Entry> out;
    for (const auto& j : ctx_.Programs().List(node, pattern)) {
      out.push_back({j.value("name", std::string()), j.value("size", std::uint64_t{0}),
                     j.value("protected", false), j.value("selected", false), j.value("hidden", false)});
    }
    return out;
  }
  std::optional<std::string> Get(const std::string& node, const std::string& name) override {
    return ctx_.Programs().Get(node, name);
  }
  void Copy(const std::string& from_node, const std::string& from, const std::string& to_node,
            const std::string& to, bool force) override {
    ctx_.Programs().Copy(from_node, from, to_node, to, force, Key("cp"));
  }
  void Rename(const std::string& node, const std::string& from, const std::string& to) override {
    ctx_.Programs().Rename(node, from, node, to, Key("mv"));
  }
  void Delete(const std::string& node, const std::string& name) override {
    ctx_.Programs().Delete(node, name, Key("rm"));
  }
  void Flag(const std::string& node, const std::string& name, const std::string& flag, bool on) override {
    ctx_.Programs().Flag(node, name, flag, on, Key(flag));
  }

 private:
  // One command may make several calls: each gets its own verb and counter in the key.
  std::string Key(const std::string& what) {
    return ctx_.IdempotencyKey("mem-" + what + std::to_string(++n_));
  }
  Context& ctx_;
  int n_ = 0;
};

// The options of every program verb: one invocation parses one verb.
struct Opts {
  std::string file, name, node = "HOST", from = "HOST", to = "HOST", dialect, type, out, pattern = "*", a, b,
                          station;
  bool force = false;
  uint32_t revision = 0;
};
using OptsPtr = std::shared_ptr<Opts>;

void AddProgramPut(CLI::App& prog, Context& ctx, const OptsPtr& o) {
  auto* put = prog.add_subcommand("put", "store FILE (a new name, or --force for a new revision)");
  put->add_option("FILE", o->file)->required();
  auto* name_opt =
      put->add_option("--name", o->name, "stored name (default: the KT-APL NAM, else the file name)");
  put->add_option("--node", o->node, "namespace: HOST or a station id");
  put->add_option("--dialect", o->dialect, cell::interp::DialectList() + " (default: detected)");
  put->add_option(
      "--type", o->type,
      "part_program, library, schedule, tool_table, fixture_offsets, inspection, data, part_model");
  put->add_flag("--force", o->force, "store a new revision of an existing name");
  put->add_flag("--json", ctx.json);
  put->callback([o, &ctx, name_opt] {
    // An explicit --name "" is a mistake, not a request for the default name.
    if (name_opt->count() > 0 && o->name.empty()) throw Exit{2, "--name: a program name cannot be empty"};
    if (!o->name.empty()) cell::names::CheckProgram(o->name);
    cell::names::CheckNode(o->node);
    std::string content = ReadProgram(o->file);
    std::string name = o->name.empty() ? NameFor(o->file, content, o->dialect) : o->name;
    cell::names::CheckProgram(name);
    cell::program_store::Client::PutOptions po;
    po.node = o->node;
    po.force = o->force;
    po.dialect = o->dialect;
    po.file_type = o->type;
    po.idempotency_key = ctx.IdempotencyKey("program-put");
    auto j = ctx.Programs().Put(name, content, po);
    PrintWarnings(j);
    if (ctx.json) {
      Print(ctx, j, {});
    } else {
      // "(709 bytes, ktapl)"; a file without a dialect shows its type ("(401 bytes, part_model)").
      std::string what = j.value("dialect", std::string());
      if (what.empty()) what = j.value("type", std::string("data"));
      std::cout << "stored " << o->node << ":" << j.value("name", name) << " revision "
                << j.value("revision", 0) << " (" << j.value("size", 0) << " bytes, " << what << ")\n";
    }
  });
}

void AddProgramGet(CLI::App& prog, Context& ctx, const OptsPtr& o) {
  auto* get = prog.add_subcommand("get", "print a program (or -o FILE)");
  get->add_option("NAME", o->name)->required();
  get->add_option("--node", o->node);
  get->add_option("--revision", o->revision, "a past revision (default: latest)")->transform(Decimal());
  get->add_option("-o,--output", o->out, "write to FILE instead of stdout");
  get->callback([o, &ctx] {
    CheckAddress(o->node, o->name);
    auto text = ctx.Programs().Get(o->node, o->name, o->revision);
    if (!text) {
      // The store's own reason (an unknown namespace, a missing revision) says more than "not found".
      ctx.Programs().Show(o->node, o->name);
      throw Exit{1, "no program '" + o->name + "' in " + o->node};
    }
    if (o->out.empty()) {
      std::cout << *text;
    } else {
      WriteLocalFile(o->out, *text);
    }
  });
}

// DESIGN §6b: the scheduler's predictions and estimates of the program on each station (docs/scheduler.md
// "Estimates"); without a scheduler on the bus, none, and predicted_why says so. The scheduler answers at
// once with what it has: a prediction not made yet is asked for then ("not predicted yet: asked for").
void AddEstimates(Context& ctx, const Opts& o, nlohmann::json& j) {
  const std::string ref = o.node == "HOST" ? o.name : o.node + ":" + o.name;
  if (!j.value("dialect", std::string()).size() || j.value("type", std::string()) == "part_model") return;
  if (!ctx.SchedulerUp(bus::Millis(2000))) {
    j["predicted_s"] = nullptr;
    j["predicted_why"] = "no scheduler on the bus: predictions are the scheduler's";
    return;
  }
  cell::SchedulerRequest r;
  r.op(cell::SCHED_PROGRAM_SHOW);
  cell::names::Assign(r.name(), ref, "program");
  const nlohmann::json e = nlohmann::json::parse(ctx.Scheduler(r).info().to_string());
  for (const char* k : {"predicted_s", "predicted_why", "estimate_s", "estimate_runs"}) j[k] = e.at(k);
}

void AddProgramShow(CLI::App& prog, Context& ctx, const OptsPtr& o) {
  auto* show = prog.add_subcommand("show", "metadata: type, dialect, NAM, UTL, UCY, revisions");
  show->add_option("NAME", o->name)->required();
  show->add_option("--node", o->node);
  show->add_flag("--json", ctx.json);
  show->callback([o, &ctx] {
    CheckAddress(o->node, o->name);
    auto j = ctx.Programs().Show(o->node, o->name);
    AddEstimates(ctx, *o, j);
    if (ctx.json) return Print(ctx, j, {});
    nlohmann::json flat = j;
    flat.erase("revisions");
    Print(ctx, flat, {});
    std::cout << "revisions:\n";
    for (auto& r : j["revisions"])
      std::cout << "  " << r["revision"] << "  " << r["created_at"].get<std::string>() << "  " << r["size"]
                << " bytes  " << r["sha256"].get<std::string>().substr(0, 16) << "\n";
  });
}

// What `program plot` runs: the program's text and where its subprograms are looked for, its dialect, and
// with a station what that station would start it with.
struct PlotRun {
  std::vector<std::string> namespaces;  // the program's and its subprograms', in order
  std::string found_in;
  cell::interp::RunOptions opt;
  cell::interp::MachineKind machine = cell::interp::MachineKind::kMachiningCentre;
};

// A station draws in its own machine's view ([machine] kind); a station file without one, in its dialect's.
cell::interp::MachineKind StationMachine(const cell::config::StationConfig& st,
                                         const cell::interp::Dialect& d) {
  try {
    const auto kind = cell::machine::LoadMachineConfig(st.file).kind;
    return kind == cell::interp::MachineKindName(cell::interp::MachineKind::kLathe)
               ? cell::interp::MachineKind::kLathe
               : cell::interp::MachineKind::kMachiningCentre;
  } catch (const cell::Error&) {
    return d.machine();
  }
}

// The station's tool table and kept variables as it publishes them (2 s), else its file's tools: a plot
// never needs the station to be up.
void StationMemory(Context& ctx, const cell::config::StationConfig& st, cell::interp::RunOptions& opt) {
  opt.tools = cell::tooltable::ToolTable(st.tools);
  if (auto t = ctx.Tools(st.id, bus::Millis(2000))) opt.tools = cell::tooltable::FromWire(*t);
  if (auto v = ctx.Variables(st.id, bus::Millis(500)))
    for (const auto& x : v->variables()) opt.variables[x.name().to_string()] = x.value();
  opt.params = st.params;
}

PlotRun PreparePlot(Context& ctx, const Opts& o, bool node_given) {
  PlotRun r;
  std::optional<cell::config::StationConfig> st;
  if (!o.station.empty()) st = cell::interp::LoadStation(o.station);
  // As the station looks programs up: its namespace, then HOST (docs/station.md); --node names one.
  r.namespaces =
      st && !node_given ? std::vector<std::string>{st->id, "HOST"} : std::vector<std::string>{o.node};
  for (const auto& ns : r.namespaces) {
    if (auto text = ctx.Programs().Get(ns, o.name)) {
      r.opt.program_text = std::move(*text);
      r.found_in = ns;
      break;
    }
  }
  if (r.found_in.empty()) {
    ctx.Programs().Show(r.namespaces.front(), o.name);  // the store's own reason, when it has one
    throw Exit{1, "no program '" + o.name + "' in " + r.namespaces.front()};
  }
  std::string dialect =
      st ? st->dialect : ctx.Programs().Show(r.found_in, o.name).value("dialect", std::string());
  if (dialect.empty()) throw Exit{1, o.name + " has no dialect: not a program to plot (give --station)"};
  const cell::interp::Dialect& d = cell::interp::DialectOrThrow(dialect);
  r.opt.dialect = std::string(d.name());
  r.opt.program_name = o.name;
  r.machine = st ? StationMachine(*st, d) : d.machine();
  if (st) StationMemory(ctx, *st, r.opt);
  auto namespaces = r.namespaces;
  r.opt.library = [&ctx, namespaces](const std::string& lib) -> std::optional<std::string> {
    for (const auto& ns : namespaces)
      if (auto text = ctx.Programs().Get(ns, lib)) return text;
    return std::nullopt;
  };
  return r;
}

// The program run through its dialect offline (no machine: probes never touch, inputs are there at once)
// and drawn; a run that stops with an error is drawn up to there and fails the verb.
void AddProgramPlot(CLI::App& prog, Context& ctx, const OptsPtr& o) {
  auto* plot = prog.add_subcommand("plot", "draw a program's toolpath as SVG (docs/plot.md)");
  plot->add_option("NAME", o->name)->required();
  auto* node =
      plot->add_option("--node", o->node, "namespace (default HOST; with --station: its own, then HOST)");
  plot->add_option("--station", o->station, "as this station runs it: its dialect, machine, tools, settings");
  plot->add_option("-o,--output", o->out, "the SVG file to write")->required();
  // It reads the station's published tools and variables: the whole cell (the noun marked it services-only
  // first; this verb's own callback runs after).
  plot->preparse_callback([&ctx](std::size_t) { ctx.host_services_only = false; });
  plot->callback([o, &ctx, node] {
    CheckAddress(o->node, o->name);
    if (!o->station.empty()) cell::names::CheckStation(o->station);
    PlotRun r = PreparePlot(ctx, *o, node->count() > 0);
    cell::interp::Plot plot({r.machine, o->name + " (" + r.opt.dialect + ", " + r.found_in +
                                            (o->station.empty() ? "" : ", station " + o->station) + ")"});
    auto run = cell::interp::StartRun(r.opt);
    cell::interp::Step s;
    for (run->NextInto(s); s.kind == cell::interp::Step::kCanon; run->NextInto(s)) plot.Add(s.canon);
    if (s.kind == cell::interp::Step::kError) plot.SetNote(s.diag.Format());
    WriteLocalFile(o->out, plot.Svg());
    if (s.kind == cell::interp::Step::kError) throw Exit{1, s.diag.Format()};
    std::cout << "wrote " << o->out << "\n";
  });
}

void AddProgramRm(CLI::App& prog, Context& ctx, const OptsPtr& o) {
  auto* rm = prog.add_subcommand("rm", "delete a program (not when protected)");
  rm->add_option("NAME", o->name)->required();
  rm->add_option("--node", o->node);
  rm->callback([o, &ctx] {
    CheckAddress(o->node, o->name);
    ctx.Programs().Delete(o->node, o->name, ctx.IdempotencyKey("program-rm"));
  });
}

void AddProgramLs(CLI::App& prog, Context& ctx, const OptsPtr& o) {
  auto* ls = prog.add_subcommand("ls", "list programs matching PATTERN (* and ?)");
  ls->add_option("PATTERN", o->pattern);
  ls->add_option("--node", o->node);
  auto page = std::make_shared<Paging>();
  AddPaging(ls, *page, false);
  ls->add_flag("--json", ctx.json);
  ls->callback([o, page, &ctx] {
    cell::names::CheckNode(o->node);
    cell::names::CheckPattern(o->pattern);
    // A viewer may not use the store's request topic: it lists what the store publishes (docs/security.md),
    // all of it by name, and takes the same page of it here.
    const bool viewer = cell::config::IdentityOverride() == "viewer";
    nlohmann::json rows;
    if (viewer) {
      rows = nlohmann::json::array();
      for (auto& f :
           cell::program_store::ListPublished(ctx.Bus(), o->node, o->pattern, cell::bus::Millis(10000)))
        if (f.value("name", std::string()) > page->after && rows.size() < page->limit) rows.push_back(f);
    } else {
      rows = ctx.Programs().List(o->node, o->pattern, page->limit, page->after);
    }
    Print(ctx, rows, {"name", "node", "type", "dialect", "revision", "size", "protected"});
  });
}

void AddProgramCopyMove(CLI::App& prog, Context& ctx, const OptsPtr& o) {
  for (std::string verb : {"cp", "mv"}) {
    auto* c = prog.add_subcommand(verb, verb == "cp" ? "copy A to B (between namespaces: --from/--to)"
                                                     : "rename A to B (between namespaces: --from/--to)");
    c->add_option("A", o->a)->required();
    c->add_option("B", o->b);
    c->add_option("--from", o->from, "source namespace (default HOST)");
    c->add_option("--to", o->to, "target namespace (default HOST)");
    if (verb == "cp") c->add_flag("--force", o->force);
    c->callback([o, &ctx, verb] {
      std::string b = o->b.empty() ? o->a : o->b;
      CheckAddress(o->from, o->a);
      CheckAddress(o->to, b);
      // The key names the verb; the store compares the request (both names and namespaces) on a replay.
      std::string key = ctx.IdempotencyKey("program-" + verb);
      if (verb == "cp")
        ctx.Programs().Copy(o->from, o->a, o->to, b, o->force, key);
      else
        ctx.Programs().Rename(o->from, o->a, o->to, b, key);
    });
  }
}

void AddProgramProtect(CLI::App& prog, Context& ctx, const OptsPtr& o) {
  for (std::string verb : {"protect", "unprotect"}) {
    auto* p =
        prog.add_subcommand(verb, verb == "protect" ? "forbid overwrite and delete" : "allow them again");
    p->add_option("NAME", o->name)->required();
    p->add_option("--node", o->node);
    p->callback([o, &ctx, verb] {
      CheckAddress(o->node, o->name);
      ctx.Programs().Protect(o->node, o->name, verb == "protect");
    });
  }
}

// Balt-System's memory commands on a station's memories (docs/dialects/balt.md, "Memories").
void AddProgramMemory(CLI::App& prog, Context& ctx, const OptsPtr& o) {
  auto* mem = prog.add_subcommand("memory",
                                  "run a Balt-System memory command (DIR COP REN DEL ATT DIF INI "
                                  "SPG REL) on STATION's memories, e.g. \"COP,P9/MP2,P2/MP3\"");
  mem->add_option("STATION", o->node)->required();
  mem->add_option("COMMAND", o->a)->required();
  mem->add_flag("--yes", o->force, "answer Y to the control's question (EXISTS DELETE???, DO YOU CONFIRM?)");
  mem->add_flag("--json", ctx.json);
  mem->callback([o, &ctx] {
    cell::names::CheckStation(o->node);
    ClientMemory backend(ctx);
    auto r = cell::program_store::RunMemoryCommand(backend, o->node, o->a, o->force);
    if (ctx.json) {
      std::cout << nlohmann::json{{"lines", r.lines}, {"message", r.message}, {"differ", r.differ}}.dump(2)
                << "\n";
    } else {
      for (const auto& l : r.lines) std::cout << l << "\n";
      std::cout << r.message << "\n";
    }
    if (r.differ) throw Exit{1, ""};
  });
}

void AddProgramImport(CLI::App& prog, Context& ctx, const OptsPtr& o) {
  auto* imp = prog.add_subcommand("import", "store every file of DIR (names: NAM or file name)");
  imp->add_option("DIR", o->file)->required();
  imp->add_option("--node", o->node);
  imp->add_flag("--force", o->force);
  imp->callback([o, &ctx] {
    cell::names::CheckNode(o->node);
    int n = 0;
    std::vector<std::filesystem::path> files;
    std::error_code ec;
    for (auto it = std::filesystem::directory_iterator(o->file, ec);
         !ec && it != std::filesystem::directory_iterator(); it.increment(ec))
      if (it->is_regular_file()) files.push_back(it->path());
    if (ec) throw Exit{1, "cannot read directory " + o->file + ": " + ec.message()};
    std::sort(files.begin(), files.end());
    // A refused file (bad name, not text, protected, exists without --force) is reported and the rest are
    // still imported; a store that cannot be reached stops the import at once.
    int refused = 0;
    for (auto& f : files) {
      try {
        std::string content = ReadProgram(f.string());
        cell::program_store::Client::PutOptions po;
        po.node = o->node;
        po.force = o->force;
        std::string name = NameFor(f.string(), content, "");
        cell::names::CheckProgram(name);
        // One command, one key per file: its place in the sorted listing (the store compares name and
        // content).
        po.idempotency_key = ctx.IdempotencyKey("program-import:" + std::to_string(n + refused));
        PrintWarnings(ctx.Programs().Put(name, content, po));
        std::cout << "stored " << o->node << ":" << name << "\n";
        ++n;
      } catch (const cell::Error& e) {
        if (e.code() == cell::Errc::kTimeout || e.code() == cell::Errc::kUnavailable) throw;
        std::cerr << "cellctl: " << f.filename().string() << ": " << e.what() << "\n";
        ++refused;
      } catch (const Exit& e) {
        std::cerr << "cellctl: " << f.filename().string() << ": " << e.message << "\n";
        ++refused;
      }
    }
    std::cout << n << " file(s) imported\n";
    if (refused > 0) throw Exit{1, std::to_string(refused) + " file(s) refused"};
  });
}

void AddProgramExport(CLI::App& prog, Context& ctx, const OptsPtr& o) {
  auto* exp = prog.add_subcommand("export", "write every program of a namespace into DIR");
  exp->add_option("DIR", o->file)->required();
  exp->add_option("--node", o->node);
  exp->callback([o, &ctx] {
    cell::names::CheckNode(o->node);
    std::filesystem::create_directories(o->file);
    int n = 0;
    for (auto& f : ctx.Programs().List(o->node, "*")) {
      std::string name = f["name"].get<std::string>();
      if (name.find('/') != std::string::npos || name == "." || name == "..")
        throw Exit{1, "cannot export '" + name + "' as a file name"};
      auto text = ctx.Programs().Get(o->node, name);
      if (!text) continue;
      WriteLocalFile((std::filesystem::path(o->file) / name).string(), *text);
      ++n;
    }
    std::cout << n << " file(s) exported\n";
  });
}

}  // namespace

void AddProgramVerbs(CLI::App& app, Context& ctx) {
  auto* prog = app.add_subcommand("program", "the program store")->require_subcommand(1);
  ServicesOnly(prog, ctx);  // but `program plot` (below)
  auto o = std::make_shared<Opts>();
  AddProgramPut(*prog, ctx, o);
  AddProgramGet(*prog, ctx, o);
  AddProgramShow(*prog, ctx, o);
  AddProgramPlot(*prog, ctx, o);
  AddProgramRm(*prog, ctx, o);
  AddProgramLs(*prog, ctx, o);
  AddProgramCopyMove(*prog, ctx, o);
  AddProgramProtect(*prog, ctx, o);
  AddProgramMemory(*prog, ctx, o);
  AddProgramImport(*prog, ctx, o);
  AddProgramExport(*prog, ctx, o);
}

}  // namespace cellctl
