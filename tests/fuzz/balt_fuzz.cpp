// libFuzzer target: any bytes as a Balt-System program, as an offsets file (FI1COR) and as a heading must
// never crash the interpreter; runs are bounded so that endless branch loops end.
#include <cstddef>
#include <cstdint>
#include <string>

#include "cell/error/error.h"
#include "cell/interp/balt.h"
#include "drain.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  const cell::interp::Dialect& balt = cell::interp::BaltDialect();
  (void)balt.ReadHeading(text, {});
  try {
    (void)balt.ParseToolTable(text, "fuzz", {});
  } catch (const cell::Error&) {
  }
  cell::interp::RunOptions opt;
  opt.program_name = "fuzz";
  opt.program_text = text;
  opt.params["MAX_IDLE_BLOCKS"] = "500";
  opt.params["ROLLOVER"] = "B";
  // Offsets with a diameter (as the cc_* and probe corpus seeds select them), so that G41/G42 and the GTL
  // profiles run with a real cutter radius, and one with a length on X.
  try {
    opt.tools = balt.ParseToolTable("1 Z100 K10\n2 X50 K0\n9 Z0 K12\n30 Z0 K6\n", "fuzz", {});
  } catch (const cell::Error&) {
    return 0;
  }
  opt.library = [](const std::string& name) -> std::optional<std::string> {
    if (name == "SUBA") return std::string("G91 X1 F100\nG90\n");
    return std::nullopt;
  };
  auto run = balt.StartRun(opt);
  cell::fuzz::Drain(*run, 2000);
  (void)run->Variables();
  return 0;
}
