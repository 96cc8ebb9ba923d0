// The DNC drip-feed benchmark (docs/dnc.md "Benchmark"): a program of 10 MB (--mb) sent through a real
// pseudo-terminal into the simulated control's 256-byte buffer, paced at 9600 baud 7E1 (960 bytes/s) times
// --scale (25: 24,000 bytes/s, so 10 MB takes about 7 minutes instead of three hours; the control's 192 bytes
// above its XOFF mark are then 8 ms, more than a loaded machine's scheduling delays). The control executes
// twice as fast as the line but stops for 5 ms every 16 KB (a long block), so XOFF/XON pace the feed.
// Prints the bytes sent, lost and changed, the rate against the line rate, and exits 1 unless nothing was
// lost or changed and the rate is at least 90% of the line's.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <fmt/format.h>

#include "cell/dnc/codes.h"
#include "cell/dnc/line.h"
#include "cell/dnc/transfer.h"
#include "sim_control.h"

using namespace cell::dnc;

namespace {

std::string Program(size_t bytes) {
  std::string p = "%\n";
  for (int n = 1; p.size() < bytes; ++n) {
    p += fmt::format("N{:06d} G01 X{}.{:03d} Y-{}.500 F{}\n", n % 1000000, n % 500, n % 1000, n % 300,
                     100 + n % 900);
  }
  return p + "M02\n";
}

}  // namespace

int main(int argc, char** argv) {
  double mb = 10, scale = 25;
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string k = argv[i];
    if (k == "--mb") mb = std::atof(argv[i + 1]);
    if (k == "--scale") scale = std::atof(argv[i + 1]);
  }
  test::Pty pty;
  Serial s = Defaults(Control::kBalt);  // ISO 7-bit even parity, 9600 baud, XON/XOFF, NUL end
  s.device = pty.slave();
  std::string text = Program(static_cast<size_t>(mb * 1e6));
  auto bytes = Encode(s.format, text);
  const double rate = LineRate(s) * scale;
  test::SimOptions so;
  so.format = s.format;
  so.line_bytes_per_s = rate;
  so.exec_bytes_per_s = 2 * rate;
  so.pause_every = 16384;
  so.pause_s = 0.005;
  try {
    auto port = TtyPort::Open(s);
    test::SimControl sim(pty, so);
    sim.StartReading();
    SendOptions o;
    o.bytes_per_s = rate;
    o.stall_timeout = std::chrono::milliseconds(5000);
    Stats st = Send(*port, bytes, o);
    sim.Join();
    size_t changed = sim.text() == text ? 0 : 1;
    double share = st.Rate() / rate;
    std::printf("drip: %zu bytes in %.1f s, %.0f bytes/s of a %.0f bytes/s line (%.1f%%, 9600 baud x %.0f)\n",
                bytes.size(), st.seconds, st.Rate(), rate, 100 * share, scale);
    std::printf("drip: %zu XOFF, %.2f s stopped, control buffer at most %zu of 256, %zu bytes lost, %s\n",
                sim.xoffs(), st.stalled_s, sim.max_fill(), sim.lost(),
                changed == 0 && sim.complete() ? "program byte-exact" : "PROGRAM CHANGED");
    if (!sim.error().empty()) std::printf("drip: the control: %s\n", sim.error().c_str());
    bool ok = sim.lost() == 0 && changed == 0 && sim.complete() && share >= 0.9;
    std::printf("drip: %s\n",
                ok ? "meets the target (0 lost, >= 90% of the line rate)" : "MISSES the target");
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "drip: %s\n", e.what());
    return 1;
  }
}
