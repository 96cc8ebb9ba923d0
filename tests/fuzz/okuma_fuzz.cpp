// libFuzzer target: any bytes as an Okuma program (and as Okuma tool data / a heading) must never crash the
// interpreter; runs are bounded so that endless programs terminate.
#include <cstddef>
#include <cstdint>
#include <string>

#include "cell/error/error.h"
#include "cell/interp/okuma.h"
#include "drain.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  const cell::interp::Dialect& okuma = cell::interp::OkumaDialect();
  (void)okuma.ReadHeading(text, {});
  (void)okuma.Classify(text);
  try {
    (void)okuma.ParseToolTable(text, "fuzz", {});
  } catch (const cell::Error&) {
  }
  cell::interp::RunOptions opt;
  opt.program_name = "fuzz";
  opt.program_text = text;
  opt.params["MAX_IDLE_BLOCKS"] = "500";
  opt.params["RS232C"] = "A Compensation Yes/No = 1 Offset No. = 3 OX = 0.02 OZ = -0.31";
  opt.variables["V1"] = 3;
  // Tools with a nose radius and tip, so that programs selecting T010101 / T020202 run nose radius
  // compensation with a real offset.
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
    t2.x_offset = 1.5;
    t2.z_offset = -20;
    opt.tools = cell::tooltable::ToolTable({t1, t2});
  }
  opt.library = [](const std::string& name) -> std::optional<std::string> {
    if (name == "O9000") return std::string("O9000\nG91 G01 X-2 F0.1\nX2\nG90\nRTS\n");
    return std::nullopt;
  };
  auto run = okuma.StartRun(opt);
  cell::fuzz::Drain(*run, 3000);
  (void)run->Variables();
  (void)run->Tools();
  return 0;
}
