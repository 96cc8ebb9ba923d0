// program_store_bus_bench: puts and gets through the bus against a running cell-program-store
// (deploy/bench.d/50-program-store.sh starts one on a private domain). Not a test.
//
//   program_store_bus_bench [--programs N] [--sql-out FILE] [--big-out FILE]
//
// Puts N programs of 2 KB (one request and one committed transaction each), gets them back, then puts
// and gets one 20 MB file (chunked), checking every byte. With --sql-out it writes the same rows as a
// sqlite3 script (one BEGIN/COMMIT per program) and with --big-out the 20 MB file, for the baseline, and
// exits without touching the bus. Prints "name seconds" lines.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include <fmt/format.h>

#include "cell/program_store/client.h"

namespace {

std::string Program(int i) {
  // A KT-APL part program of 2 KB.
  std::string s = fmt::format("%\n(NAM,BENCH {:06d})\n(UTL,1001,1002)\n(UCY,90)\n", i);
  for (int n = 10; s.size() < 2000; n += 10)
    s += fmt::format("N{} G1 X{}.{:03d} Y-{}.5 F250\n", n, i % 500, n % 1000, n);
  s += "N99990 M30\n";
  s.resize(2048, ' ');
  s.back() = '\n';
  return s;
}

std::string Big() {
  std::string s;
  s.reserve(20u << 20);
  for (int i = 0; s.size() < (20u << 20); ++i)
    s += fmt::format("row {:08d} of the big data file: 0123456789 abcdefghijklmnopqrstuvwxyz\n", i);
  s.resize(20u << 20);
  s.back() = '\n';
  return s;
}

double Since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  int programs = 10000;
  std::string sql_out, big_out;
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--programs")
      programs = std::atoi(argv[i + 1]);
    else if (a == "--sql-out")
      sql_out = argv[i + 1];
    else if (a == "--big-out")
      big_out = argv[i + 1];
    else {
      std::fprintf(stderr,
                   "usage: program_store_bus_bench [--programs N] [--sql-out FILE] [--big-out FILE]\n");
      return 2;
    }
  }
  try {
    std::string big = Big();
    if (!sql_out.empty()) {
      std::ofstream sql(sql_out);
      sql << "PRAGMA journal_mode=WAL;\nPRAGMA synchronous=FULL;\n"
             "CREATE TABLE programs(name TEXT PRIMARY KEY, content BLOB NOT NULL);\n";
      for (int i = 0; i < programs; ++i) {
        std::string p = Program(i);  // no quotes in it
        sql << "BEGIN;\nINSERT INTO programs VALUES('BENCH " << fmt::format("{:06d}", i) << "','" << p
            << "');\nCOMMIT;\n";
      }
    }
    if (!big_out.empty()) std::ofstream(big_out, std::ios::binary) << big;
    if (!sql_out.empty() || !big_out.empty()) return 0;  // only the baseline's input

    cell::bus::Participant bus("program_store_bus_bench");
    cell::program_store::Client client(bus, cell::bus::Millis(60000));
    if (!client.WaitForServer(cell::bus::Millis(30000)))
      throw cell::Error(cell::Errc::kUnavailable, "no program store");
    cell::program_store::Client::PutOptions o;
    auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < programs; ++i) client.Put(fmt::format("BENCH {:06d}", i), Program(i), o);
    double put_s = Since(t0);
    t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < programs; ++i) {
      auto got = client.Get("HOST", fmt::format("BENCH {:06d}", i));
      if (!got || *got != Program(i))
        throw cell::Error(cell::Errc::kInternal, fmt::format("program {} differs", i));
    }
    double get_s = Since(t0);
    t0 = std::chrono::steady_clock::now();
    client.Put("BENCH BIG", big, o);
    double big_put_s = Since(t0);
    t0 = std::chrono::steady_clock::now();
    auto got = client.Get("HOST", "BENCH BIG");
    double big_get_s = Since(t0);
    if (!got || *got != big) throw cell::Error(cell::Errc::kInternal, "the 20 MB file came back different");
    std::printf("programs %d\nput_s %.3f\nget_s %.3f\nbig_put_s %.3f\nbig_get_s %.3f\n", programs, put_s,
                get_s, big_put_s, big_get_s);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "program_store_bus_bench: %s\n", e.what());
    return 1;
  }
}
