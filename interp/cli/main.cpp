// cell-interp: the offline front door of the interpreter (DESIGN §4 "Offline CLI contract").
//   cell-interp --dialect D [--tools FILE] [--params FILE] [--lib DIR] [--probe-model FILE] [--listing]
//   [--svg FILE] PROGRAM
// --svg also draws the run's toolpath into FILE (docs/plot.md), also for a run that stops with an error.
// Exit 0: ran to its end; 1: program error (diagnostic on stderr); 2: usage error or unimplemented dialect.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cell/error/error.h"
#include "cell/interp/interp.h"
#include "cell/interp/plot.h"
#include "offline_environment.h"

namespace {

std::string UsageLine() {
  return "usage: cell-interp --dialect " + cell::interp::DialectChoices() +
         " [--tools FILE] [--params FILE] [--lib DIR] [--probe-model FILE] [--listing] [--svg FILE] PROGRAM";
}

int Usage(const std::string& why) {
  std::cerr << "cell-interp: " << why << "\n" << UsageLine() << "\n";
  return 2;
}

bool ReadFile(const std::string& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  in.seekg(0, std::ios::end);
  std::streamoff size = in.tellg();
  if (size < 0) return false;
  in.seekg(0, std::ios::beg);
  out.resize(static_cast<size_t>(size));
  in.read(out.data(), size);
  return static_cast<bool>(in) || in.eof();
}

// The plot of the run so far into `path`; false when it cannot be written.
bool WriteSvg(const std::string& path, const cell::interp::Plot& plot) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << plot.Svg();
  out.close();
  return static_cast<bool>(out);
}

}  // namespace

int main(int argc, char** argv) {
  std::string dialect, tools, params, lib, probe_model, program, svg;
  bool listing = false;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto value = [&](std::string& dst) -> bool {
      if (i + 1 >= argc) return false;
      dst = argv[++i];
      return true;
    };
    if (a == "--help" || a == "-h") {
      std::cout << UsageLine() << "\n";
      return 0;
    } else if (a == "--dialect") {
      if (!value(dialect)) return Usage("--dialect needs a value");
    } else if (a == "--tools") {
      if (!value(tools)) return Usage("--tools needs a file");
    } else if (a == "--params") {
      if (!value(params)) return Usage("--params needs a file");
    } else if (a == "--lib") {
      if (!value(lib)) return Usage("--lib needs a directory");
    } else if (a == "--probe-model") {
      if (!value(probe_model)) return Usage("--probe-model needs a file");
    } else if (a == "--svg") {
      if (!value(svg)) return Usage("--svg needs a file");
    } else if (a == "--listing") {
      listing = true;
    } else if (a.size() > 1 && a[0] == '-') {
      return Usage("unknown option " + a);
    } else if (program.empty()) {
      program = a;
    } else {
      return Usage("only one PROGRAM may be given");
    }
  }
  if (dialect.empty()) return Usage("--dialect is required");
  const cell::interp::Dialect* d = cell::interp::FindDialect(dialect);
  if (!d) return Usage("unknown dialect '" + dialect + "'");
  if (!d->implemented()) {
    std::cerr << "cell-interp: dialect '" << dialect << "' is not implemented yet\n";
    return 2;
  }
  if (program.empty()) return Usage("PROGRAM is required");

  cell::interp::RunOptions opt;
  opt.dialect = std::string(d->name());
  opt.program_name = program;
  try {
    if (listing) {
      std::string text;
      if (!ReadFile(program, text)) return Usage("cannot read " + program);
      opt.program_text = d->ImportListing(text);
    } else {
      opt.program = cell::interp::ProgramText::MapFile(program);  // memory flat however long the program
    }
  } catch (const cell::Error& e) {
    return Usage(e.what());
  }
  if (!tools.empty()) {
    std::string text;
    if (!ReadFile(tools, text)) return Usage("cannot read " + tools);
    try {
      opt.tools = d->ParseToolTable(text, tools, {});
    } catch (const cell::Error& e) {
      return Usage("bad tool table: " + std::string(e.what()));
    }
  }
  if (!params.empty()) {
    std::string text;
    if (!ReadFile(params, text)) return Usage("cannot read " + params);
    std::istringstream in(text);
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
      ++n;
      auto hash = line.find('#');
      if (hash != std::string::npos) line.resize(hash);
      while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
      size_t b = line.find_first_not_of(" \t");
      if (b == std::string::npos) continue;
      auto eq = line.find('=');
      if (eq == std::string::npos) return Usage(params + ":" + std::to_string(n) + ": expected NAME=VALUE");
      opt.params[line.substr(b, eq - b)] = line.substr(eq + 1);
    }
  }
  if (!lib.empty()) {
    if (!std::filesystem::is_directory(lib)) return Usage("--lib " + lib + " is not a directory");
    std::vector<std::string> exts = {""};
    for (std::string_view e : d->extensions()) exts.emplace_back(e);
    opt.library = [lib, exts](const std::string& name) -> std::optional<std::string> {
      for (const std::string& ext : exts) {
        std::string text;
        if (ReadFile(lib + "/" + name + ext, text)) return text;
      }
      return std::nullopt;
    };
  }
  cell::interp::OfflineEnvironment env;
  if (std::string why = env.Configure(opt.params); !why.empty()) return Usage(params + ": " + why);
  if (!probe_model.empty()) {
    std::string text;
    if (!ReadFile(probe_model, text)) return Usage("cannot read " + probe_model);
    try {
      env.SetPartModel(cell::partmodel::ParsePartModel(text, probe_model));
    } catch (const cell::Error& e) {
      return Usage("bad probe model: " + std::string(e.what()));
    }
  }
  opt.env = &env;

  std::unique_ptr<cell::interp::Run> run;
  try {
    run = d->StartRun(opt);
  } catch (const cell::Error& e) {
    std::cerr << "cell-interp: " << e.what() << "\n";
    return 2;
  }
  // Lines are gathered in one buffer and written in large pieces (the output of a long program is most of
  // the CLI's work).
  std::string out;
  out.reserve(1 << 17);
  auto flush = [&out] {
    std::fwrite(out.data(), 1, out.size(), stdout);
    out.clear();
  };
  // The plot draws in the station's view of the dialect's machine kind (a lathe's half-section).
  std::optional<cell::interp::Plot> plot;
  if (!svg.empty())
    plot.emplace(cell::interp::PlotOptions{d->machine(), std::filesystem::path(program).filename().string() +
                                                             " (" + std::string(d->name()) + ")"});
  auto finish = [&](int code) {
    flush();
    std::fflush(stdout);
    if (plot && !WriteSvg(svg, *plot)) {
      std::cerr << "cell-interp: cannot write " << svg << "\n";
      return 2;
    }
    return code;
  };
  cell::interp::Step s;
  for (;;) {
    if (const cell::interp::Canon* c = run->NextInPlace(s)) {  // written where the run keeps it: no copy
      cell::interp::AppendJsonLine(out, *c);
      out += '\n';
      if (plot) plot->Add(*c);
      if (out.size() > (1 << 16)) flush();
    } else if (s.kind == cell::interp::Step::kEnd) {
      return finish(0);
    } else {
      if (plot) plot->SetNote(s.diag.Format());
      const int code = finish(1);
      std::cerr << s.diag.Format() << "\n";
      return code;
    }
  }
}
