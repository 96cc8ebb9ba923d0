// program_store_put_stream: a program store client for the crash test.
//
//   program_store_put_stream --count N [--size BYTES]
//     puts S000000, S000001, ... (StreamContent) into HOST, each with its name as idempotency key;
//     a failed call (store down) is retried with the same key until it succeeds. After each
//     acknowledged put it prints "ACK <name> <sha256>" and flushes.
//   program_store_put_stream --big NAME --size BYTES [--chunk-delay-ms MS]
//     streams one file chunk by chunk over the raw request/reply protocol, printing "CHUNK <i>"
//     after each acknowledged chunk (the test kills it half way), then "DONE".
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/program_store/client.h"
#include "cell/program_store/sha256.h"
#include "put_stream_content.h"

namespace ps = cell::program_store;

int main(int argc, char** argv) {
  int count = 0, delay_ms = 0;
  size_t size = 2048;
  std::string big;
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string a = argv[i], v = argv[i + 1];
    if (a == "--count")
      count = std::atoi(v.c_str());
    else if (a == "--size")
      size = std::strtoull(v.c_str(), nullptr, 10);
    else if (a == "--big")
      big = v;
    else if (a == "--chunk-delay-ms")
      delay_ms = std::atoi(v.c_str());
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  cell::bus::Participant bus("program_store_put_stream");
  if (!big.empty()) {
    cell::bus::Client<cell::ProgramRequest, cell::ProgramReply> c(bus, cell::bus::topics::kProgramStore);
    std::string content = cell::testing::StreamContent(big, size);
    cell::ProgramRequest req;
    req.op(cell::PROGRAM_PUT_CHUNK);
    req.node("HOST");
    req.name(big);
    req.stream_id("put-stream-" + big);
    size_t n = (content.size() + ps::kChunkBytes - 1) / ps::kChunkBytes;
    for (size_t i = 0; i < n; ++i) {
      size_t off = i * ps::kChunkBytes, len = std::min(ps::kChunkBytes, content.size() - off);
      req.chunk_index(static_cast<uint32_t>(i));
      req.last_chunk(i + 1 == n);
      req.data().assign(content.begin() + static_cast<long>(off),
                        content.begin() + static_cast<long>(off + len));
      auto rep = c.Call(req, cell::bus::Millis(30000));
      cell::bus::ThrowIfError(rep);
      std::printf("CHUNK %zu\n", i);
      std::fflush(stdout);
      if (delay_ms) std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    }
    std::printf("DONE\n");
    return 0;
  }
  ps::Client client(bus, cell::bus::Millis(2000));
  for (int i = 0; i < count; ++i) {
    std::string name = cell::testing::StreamName(i);
    std::string content = cell::testing::StreamContent(name, size);
    ps::Client::PutOptions o;
    o.idempotency_key = "put-stream:" + name;
    auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (true) {
      try {
        client.Put(name, content, o);
        break;
      } catch (const cell::Error& e) {
        // The store is down or restarting: retry with the same key (never twice in effect).
        if (e.code() != cell::Errc::kUnavailable && e.code() != cell::Errc::kTimeout) {
          std::fprintf(stderr, "put %s: %s\n", name.c_str(), e.what());
          return 1;
        }
        if (std::chrono::steady_clock::now() > deadline) {
          std::fprintf(stderr, "put %s: gave up: %s\n", name.c_str(), e.what());
          return 1;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    }
    std::printf("ACK %s %s\n", name.c_str(), ps::Sha256Hex(content).c_str());
    std::fflush(stdout);
  }
  return 0;
}
