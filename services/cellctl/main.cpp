// cellctl: the cell's supervisor CLI (DESIGN.md §6). `cellctl <noun> <verb> [args]`.
#include <iostream>

#include "cell/bus/backend.h"
#include "context.h"

int main(int argc, char** argv) {
  cell::bus::SilenceDdsLog();  // stdout is the command's output, stderr its one-line reason
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
