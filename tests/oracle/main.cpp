// cell-oracle-gen: the LinuxCNC differential's command line (docs/testing.md "LinuxCNC differential").
//   cell-oracle-gen gen --dialect D --seed S --blocks N --out PREFIX   PREFIX.<ext>, PREFIX.ngc,
//   PREFIX.params cell-oracle-gen check --dialect D|all --seed S --blocks N [--chunk M] [--interp PATH]
//   [--rs274 PATH]
//                   [--report] [--keep DIR] [--plant]
// check runs cell-interp on each generated program and rs274 on its NGC twin and compares every move; it
// exits 1 on any disagreement (--report: prints the agreement per dialect and exits 0 unless a run could not
// start). `check --comp` (comp.cpp): the same under cutter radius compensation (Balt-System, KT-APL) and
// tool-nose radius compensation (EMCO, Okuma).
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "cell/oracle/oracle.h"
#include "run.h"

namespace fs = std::filesystem;
using namespace cell::oracle;

namespace {

struct Options {
  std::string command, dialect = "all", out, interp = "cell-interp", rs274, keep;
  std::uint64_t seed = 1;
  int blocks = 1000, chunk = 250, show = 3;
  bool report = false, plant = false, comp = false;
};

bool ParseArgs(int argc, char** argv, Options& o) {
  if (argc < 2) return false;
  o.command = argv[1];
  for (int i = 2; i < argc; ++i) {
    std::string a = argv[i];
    auto value = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
    if (a == "--dialect")
      o.dialect = value();
    else if (a == "--seed")
      o.seed = std::strtoull(value().c_str(), nullptr, 10);
    else if (a == "--blocks")
      o.blocks = std::atoi(value().c_str());
    else if (a == "--chunk")
      o.chunk = std::atoi(value().c_str());
    else if (a == "--out")
      o.out = value();
    else if (a == "--interp")
      o.interp = value();
    else if (a == "--rs274")
      o.rs274 = value();
    else if (a == "--keep")
      o.keep = value();
    else if (a == "--show")
      o.show = std::atoi(value().c_str());
    else if (a == "--report")
      o.report = true;
    else if (a == "--plant")
      o.plant = true;
    else if (a == "--comp")
      o.comp = true;
    else
      return false;
  }
  return (o.command == "gen" || o.command == "check") && o.blocks > 0 && o.chunk > 0;
}

std::string FindRs274(const std::string& given) {
  if (!given.empty()) return access(given.c_str(), X_OK) == 0 ? given : "";
  std::stringstream path(std::getenv("PATH") ? std::getenv("PATH") : "/usr/bin");
  std::string dir;
  while (std::getline(path, dir, ':'))
    if (access((dir + "/rs274").c_str(), X_OK) == 0) return dir + "/rs274";
  return "";
}

struct Written {
  Program program;
  fs::path dialect_file, ngc_file, params_file;
};

Written WriteProgram(const Module& mod, std::uint64_t seed, int count, const fs::path& prefix) {
  Caps caps = mod.Capabilities(seed);
  auto blocks = Generate(caps, seed, count);
  Written w{mod.Write(blocks, seed), {}, {}, {}};
  NgcText ngc = WriteNgc(blocks, caps);
  w.program.ngc_text = ngc.text;
  w.program.blocks_ngc = ngc.blocks;
  w.dialect_file = prefix.string() + "." + mod.Extension();
  w.ngc_file = prefix.string() + ".ngc";
  Spit(w.dialect_file, w.program.dialect_text);
  Spit(w.ngc_file, w.program.ngc_text);
  if (!w.program.params.empty()) {
    w.params_file = prefix.string() + ".params";
    Spit(w.params_file, w.program.params);
  }
  return w;
}

// The generated block a line of the dialect program belongs to (the header comes first, the end block last).
std::size_t BlockOfLine(const Program& p, int line) {
  auto lines = [](const std::string& t) { return static_cast<int>(std::count(t.begin(), t.end(), '\n')); };
  int first = lines(p.dialect_text) - 1;
  for (const auto& b : p.blocks_dialect) first -= lines(b) + 1;
  int at = first + 1;  // 1-based line of block 0
  for (std::size_t i = 0; i < p.blocks_dialect.size(); ++i) {
    at += lines(p.blocks_dialect[i]) + 1;
    if (line < at) return i;
  }
  return p.blocks_dialect.size();
}

struct Tally {
  long moves = 0, agreeing = 0;
  int programs = 0, disagreeing = 0;
};

// Runs both interpreters on one program; the agreeing moves are counted up to the first disagreement.
bool CheckProgram(const Options& o, const Module& mod, const std::string& rs274, std::uint64_t seed,
                  int count, const fs::path& dir, Tally& t) {
  for (const char* f : {"cell.out", "cell.err", "canon.out", "rs274.log"}) fs::remove(dir / f);
  Written w = WriteProgram(mod, seed, count, dir / "prog");
  std::string args =
      " --dialect " + mod.Name() + (w.params_file.empty() ? "" : " --params " + Quote(w.params_file));
  int rc = Shell(Quote(o.interp) + args + " " + Quote(w.dialect_file) + " >" + Quote(dir / "cell.out") +
                 " 2>" + Quote(dir / "cell.err"));
  Spit(dir / "tool.tbl", "");
  Spit(dir / "rs274ngc.var", "");
  // HOME: rs274 maps its tool table at $HOME/.tool.mmap (truncated at start), so two runs with one HOME
  // die of SIGBUS; each run gets its own.
  Shell("cd " + Quote(dir) + " && HOME=" + Quote(dir) + " " + Quote(rs274) +
        " -g -t tool.tbl -v rs274ngc.var prog.ngc canon.out >rs274.log 2>&1");
  bool lathe = mod.Capabilities(seed).lathe;
  std::string err;
  auto cell = ParseCellInterp(Slurp(dir / "cell.out"), lathe, &err);
  auto ngc = ParseRs274(Slurp(dir / "canon.out"), lathe, &err);
  DropStill(cell);
  DropStill(ngc);
  InverseToPerMinute(cell);
  if (o.plant && ngc.size() > 5) ngc[5].end[0] += 0.01;  // shows the comparer fails on a wrong value
  std::string log = Slurp(dir / "rs274.log");
  // A move that differs before either side stopped is the finding; else the refusal is.
  std::optional<Disagreement> d = Compare(cell, ngc, w.program.inch_anywhere ? 2e-3 : 1e-3);
  bool before_stop = d && d->index < std::min(cell.size(), ngc.size());
  if (!err.empty())
    d = Disagreement{0, "output", err};
  else if (log.find_first_not_of("executing\n") != std::string::npos && !before_stop)
    d = Disagreement{ngc.size(), "rs274 refused", log};
  else if (rc != 0 && !before_stop)
    d = Disagreement{cell.size(), "cell-interp refused", Slurp(dir / "cell.err")};
  t.programs++;
  t.moves += count;
  if (!d) {
    t.agreeing += count;
    return true;
  }
  t.agreeing += static_cast<long>(d->index);
  if (t.disagreeing++ < o.show) {
    std::size_t bi = d->index < cell.size() ? BlockOfLine(w.program, cell[d->index].line) : d->index;
    auto block = [&](const std::vector<std::string>& v) { return bi < v.size() ? v[bi] : "(none)"; };
    std::cout << mod.Name() << ": program seed " << seed << ", move " << d->index + 1 << " (block " << bi + 1
              << "): " << d->field << " differs\n  " << mod.Name() << ": " << block(w.program.blocks_dialect)
              << "\n  NGC:  " << block(w.program.blocks_ngc) << "\n  " << d->detail << "\n";
    if (!o.keep.empty()) {
      fs::create_directories(o.keep);
      fs::path keep = fs::path(o.keep) / (mod.Name() + "-" + std::to_string(seed));
      WriteProgram(mod, seed, count, keep);
      std::cout << "  kept as " << keep.string() << ".*\n";
    }
  }
  return false;
}

int Check(const Options& o) {
  std::string rs274 = FindRs274(o.rs274);
  if (rs274.empty()) {
    std::cout
        << "oracle: rs274 not found (LinuxCNC's interpreter, Debian linuxcnc-uspace: deploy/install-deps)\n";
    return 1;
  }
  std::vector<std::string> names = o.dialect == "all" ? ModuleNames() : std::vector<std::string>{o.dialect};
  char tmpl[] = "/tmp/cell-oracle.XXXXXX";
  if (!mkdtemp(tmpl)) return 2;
  fs::path dir = tmpl;
  bool all_agree = true;
  if (o.comp) {
    // --dialect all, one dialect, or a list (balt,ktapl: the mills; emco,okuma: the lathes' nose
    // compensation).
    if (o.dialect != "all") {
      names.clear();
      std::stringstream list(o.dialect);
      for (std::string d; std::getline(list, d, ',');) names.push_back(d);
    }
    for (const std::string& name : names) {
      if (name != "balt" && name != "ktapl" && name != "emco" && name != "okuma") {
        std::cout << "oracle: --comp has no dialect " << name << "\n";
        return 2;
      }
      CompTally t = CompCheck(PropRun{o.interp, o.keep, o.seed, o.blocks, o.plant}, rs274, name, dir, o.show);
      std::printf(
          "%s comp: %d of %d programs agree (%d contour blocks, %ld moves compared; %d disagree, %d refused "
          "by rs274, %d by cell-interp, %d by the manual's alarm; %d corner points at a small turn not "
          "compared)\n",
          name.c_str(), t.agreeing, t.programs, t.blocks, t.moves, t.disagreeing, t.rs274_refused,
          t.cell_refused, t.cell_alarm, t.bent);
      if (name == "ktapl") std::printf("ktapl comp: %d of the programs under G46\n", t.bypassed);
      // rs274 refusing a contour (its own gouge check at a concave corner) is counted, not failed.
      all_agree = all_agree && t.disagreeing == 0 && t.cell_refused == 0;
    }
    fs::remove_all(dir);
    return all_agree || o.report ? 0 : 1;
  }
  for (const std::string& name : names) {
    const Module* mod = FindModule(name);
    if (!mod) {
      std::cout << "oracle: no module for dialect " << name << "\n";
      return 2;
    }
    Tally t;
    for (int done = 0, i = 0; done < o.blocks; done += o.chunk, ++i) {
      int count = std::min(o.chunk, o.blocks - done);
      all_agree = CheckProgram(o, *mod, rs274, ProgramSeed(o.seed, name, i), count, dir, t) && all_agree;
    }
    std::printf(
        "%s: %.3f%% agreement (%ld of %ld blocks up to each program's first disagreement; %d of %d programs "
        "disagree)\n",
        name.c_str(), 100.0 * t.agreeing / std::max(1L, t.moves), t.agreeing, t.moves, t.disagreeing,
        t.programs);
  }
  fs::remove_all(dir);
  return all_agree || o.report ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "prop") return Properties(argc, argv);
  if (argc > 1 && std::string(argv[1]) == "parts") return Parts(argc, argv);
  Options o;
  if (!ParseArgs(argc, argv, o)) {
    std::cerr
        << "usage: cell-oracle-gen gen --dialect D --seed S --blocks N --out PREFIX\n"
           "       cell-oracle-gen check --dialect D|all --seed S --blocks N [--chunk M] [--interp PATH]\n"
           "                       [--rs274 PATH] [--report] [--keep DIR] [--show N] [--plant]\n"
           "                       [--comp]   (cutter and nose compensation: --dialect D[,D..]|all)\n"
           "       cell-oracle-gen prop --property absinc|units|subprogram|transforms|nogouge|all --dialect "
           "D|all "
           "--seed S "
           "--blocks N\n"
           "                       [--chunk M] [--interp PATH] [--keep DIR]\n"
           "       cell-oracle-gen parts [--dir DIR] [--part NAME] [--interp PATH] [--verbose] [--plant]\n";
    return 2;
  }
  if (o.command == "gen") {
    const Module* mod = FindModule(o.dialect);
    if (!mod || o.out.empty()) {
      std::cerr << "cell-oracle-gen: gen needs --dialect "
                << "(one of the modules) and --out\n";
      return 2;
    }
    WriteProgram(*mod, o.seed, o.blocks, o.out);
    return 0;
  }
  return Check(o);
}
