// libFuzzer target: any bytes as a KT-APL program (and as a tool table / heading) must never crash the
// interpreter; runs are bounded so that endless programs terminate.
#include <cstddef>
#include <cstdint>
#include <string>

#include "cell/error/error.h"
#include "cell/interp/ktapl.h"
#include "drain.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  const cell::interp::Dialect& ktapl = cell::interp::KtaplDialect();
  (void)ktapl.ReadHeading(text, {});
  try {
    (void)ktapl.ParseToolTable(text, "fuzz", {});
  } catch (const cell::Error&) {
  }
  cell::interp::RunOptions opt;
  opt.program_name = "fuzz";
  opt.program_text = text;
  opt.params["MAX_IDLE_BLOCKS"] = "500";
  // Tools with a diameter, so that programs selecting T1/T2 (as the cc_* corpus seeds do) run cutter
  // compensation with a real offset, including a negative (preset) one.
  {
    cell::tooltable::ToolEntry t1;
    t1.tool = "1";
    t1.socket = 1;
    t1.length = 100;
    t1.diameter = 10;
    cell::tooltable::ToolEntry t2 = t1;
    t2.tool = "2";
    t2.socket = 2;
    t2.diameter = -0.5;
    opt.tools = cell::tooltable::ToolTable({t1, t2});
  }
  opt.library = [](const std::string& name) -> std::optional<std::string> {
    if (name == "LIBSUB") return std::string("(DFS,LIBSUB)\nG91X1.F0\n(END)\n");
    return std::nullopt;
  };
  auto run = ktapl.StartRun(opt);
  cell::fuzz::Drain(*run, 2000);
  return 0;
}
