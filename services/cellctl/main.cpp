// cellctl: the cell's supervisor CLI (DESIGN.md §6). `cellctl <noun> <verb> [args]`.
#include <iostream>

#include "cell/bus/backend.h"
#include "cell/bus/exit.h"
#include "cell/log/log.h"
#include "context.h"

namespace {

// The verb, with the context (and its bus participant) gone when it returns.
int Run(int argc, char** argv) {
  CLI::App app{"cellctl: supervise a DDS machining cell"};
  app.require_subcommand(1);
  cellctl::Context ctx;
  cellctl::AddProgramVerbs(app, ctx);
  cellctl::AddStationVerbs(app, ctx);
  cellctl::AddFmsVerbs(app, ctx);
  cellctl::AddJobVerbs(app, ctx);
  cellctl::AddInspectVerbs(app, ctx);
  cellctl::AddCellVerbs(app, ctx);
  cellctl::AddPkiVerbs(app, ctx);
  cellctl::AddDncVerbs(app, ctx);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "cellctl: " << e.what() << "\n";
    return 2;
  } catch (const cellctl::Exit& e) {
    if (!e.message.empty()) std::cerr << "cellctl: " << e.message << "\n";
    return e.code;
  } catch (const cell::Error& e) {
    std::cerr << "cellctl: " << ctx.Explain(e) << "\n";
    return e.code() == cell::Errc::kInvalidArgument ? 2 : 1;
  } catch (const std::exception& e) {
    std::cerr << "cellctl: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  cell::bus::SilenceDdsLog();  // stdout is the command's output, stderr its one-line reason
  // So the bus's own lines go to stderr, warnings only (spdlog's default logger writes every level to stdout:
  // a peer lost during `station ls --json` once broke its JSON).
  cell::log::Options log;
  log.level = spdlog::level::warn;
  cell::log::Init("cellctl", {}, log);
  // Run's participant has said goodbye; the DDS library's exit-time teardown has nothing left to do.
  cell::bus::ExitProcess(Run(argc, argv));
}
