// inspection_store_bench: how long a program's file close waits for durability (issue 14: "file close to
// durable acknowledgement (L1050 set) median and p99 over the bus, against a bare bus round trip in the same
// run"). Not a test; deploy/bench.d/86-inspection-store.sh starts a cell-inspection-writer on CELL_DOMAIN
// with its own CELL_DATA_DIR and runs this against it.
//
//   inspection_store_bench COUNT
//
// STORE_FILE is what the station's ProgramFiles sends at a CLF/G37 and waits for before L1050 is set: the
// writer writes a temporary file, fsyncs it, renames it and fsyncs the folder before it answers. The
// baseline is a CAT of a file that does not exist: the same client, topics and writer, no disk write.
// Each file is a 15-line inspection file (about 330 bytes, the shape the probe test writes) under a new name,
// so the idempotency cache never answers. Prints
//   RESULT store|bare MEDIAN_US P99_US
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/idl/inspection.h"

namespace bus = cell::bus;
using Clock = std::chrono::steady_clock;

namespace {

constexpr const char* kFile =
    "CONTROL SERIAL NUMBER = 345879\nPALLET CODE/PART NUMBER = 1\n26:11:24 20:45\n"
    "------------------------------\nN50\nZ SURFACE = 10.000000\n\nN80\nX SURFACE SEPARATION = 40.100000\n"
    "X CENTER = 200.05000\n\nN90\nY SURFACE SEPARATION = 40.100000\nY CENTER = 99.960000\n\n";

void Report(const char* what, std::vector<double> us) {
  std::sort(us.begin(), us.end());
  const double median = us[us.size() / 2];
  const double p99 = us[std::min(us.size() - 1, us.size() * 99 / 100)];
  std::printf("RESULT %s %.1f %.1f\n", what, median, p99);
}

}  // namespace

int main(int argc, char** argv) {
  const int count = argc > 1 ? std::atoi(argv[1]) : 500;
  if (count < 10) {
    std::fprintf(stderr, "usage: inspection_store_bench COUNT (>= 10)\n");
    return 2;
  }
  bus::Participant p("inspection-store-bench");
  bus::Client<cell::InspectionRequest, cell::InspectionReply> c(p, bus::topics::kInspection);
  if (!c.WaitForServer(bus::Millis(10000))) {
    std::fprintf(stderr, "no cell-inspection-writer on the bus\n");
    return 1;
  }
  auto store = [&](int i) {
    cell::InspectionRequest r;
    r.op(cell::INSPECTION_STORE_FILE);
    r.hdr().idempotency_key("bench-" + std::to_string(getpid()) + "-" + std::to_string(i));
    r.file().file("BENCH" + std::to_string(i));
    r.file().station("KT01");
    r.file().format(cell::INSPECTION_KT_TEXT);
    r.file().text(kFile);
    r.file().closed(true);
    bus::ThrowIfError(c.Call(r, bus::Millis(10000)));
  };
  auto bare = [&] {  // answered "not found" after one stat(2): the round trip and nothing else
    cell::InspectionRequest r;
    r.op(cell::INSPECTION_CAT);
    r.name("KT01/NO-SUCH-FILE");
    (void)c.Call(r, bus::Millis(10000));
  };
  for (int i = 0; i < 20; ++i) {  // warm up both paths
    store(-1 - i);
    bare();
  }
  std::vector<double> s, l;
  for (int i = 0; i < count; ++i) {  // interleaved, so both see the same machine load
    auto t0 = Clock::now();
    store(i);
    auto t1 = Clock::now();
    bare();
    auto t2 = Clock::now();
    s.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    l.push_back(std::chrono::duration<double, std::micro>(t2 - t1).count());
  }
  Report("store", s);
  Report("bare", l);
  return 0;
}
