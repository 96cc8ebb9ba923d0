// libFuzzer target: any bytes as an EMCO program (as tape and through the listing importer), as a tool data
// file and as a heading must never crash the interpreter; runs are bounded so that endless G27 loops end.
#include <cstddef>
#include <cstdint>
#include <string>

#include "cell/error/error.h"
#include "cell/interp/emco.h"
#include "drain.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  const cell::interp::Dialect& emco = cell::interp::EmcoDialect();
  (void)emco.ReadHeading(text, {});
  try {
    (void)emco.ParseToolTable(text, "fuzz", {});
  } catch (const cell::Error&) {
  }
  // Corrections with a nose radius and a tip code, so that programs selecting T0101/T0202 (as the corpus
  // does) run tool-nose radius compensation with real offsets; T0303 has no radius (ALARM 350).
  cell::interp::RunOptions opt;
  opt.program_name = "fuzz";
  opt.params["MAX_IDLE_BLOCKS"] = "500";
  {
    cell::tooltable::ToolEntry t1;
    t1.tool = "1";
    t1.socket = 1;
    t1.nose_radius = 0.8;
    t1.tip = 3;
    cell::tooltable::ToolEntry t2 = t1;
    t2.tool = "2";
    t2.socket = 2;
    t2.nose_radius = 0.4;
    t2.tip = 2;
    t2.x_offset = 10;
    t2.z_offset = -20;
    cell::tooltable::ToolEntry t3 = t1;
    t3.tool = "3";
    t3.socket = 3;
    t3.nose_radius = 0;
    opt.tools = cell::tooltable::ToolTable({t1, t2, t3});
  }
  opt.library = [](const std::string& name) -> std::optional<std::string> {
    if (name == "O0090") return std::string("O0090\nN0000 G00 U-1.\nN0010 M17\n");
    return std::nullopt;
  };
  for (int form = 0; form < 2; ++form) {
    opt.program_text = text;
    if (form == 1) opt.program_text = emco.ImportListing(text);
    auto run = emco.StartRun(opt);
    cell::fuzz::Drain(*run, 2000);
    (void)run->Variables();
  }
  return 0;
}
